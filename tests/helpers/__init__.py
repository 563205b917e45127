"""What the tests share: independent references (a pinhole camera from words and OpenCV's
functions, the thesis's tables, labelled scenes), one way to run the ``gsrwt`` command, one
reader of its tables. Nothing here imports a test module."""
