"""Tests of ``gsrwt_cli/batch/``: jobs, workers, executors, reruns, and the rows of a batch
under every fault."""
