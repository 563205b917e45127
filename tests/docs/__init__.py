"""Tests of the documentation: the README, docs/ and every ``--help`` tell the truth."""
