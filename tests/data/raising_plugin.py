"""A plug-in that fails while it loads (tests/python/test_python_strategies.py): the command line
must report the file and the Python exception, with exit code 2."""
import plydem  # noqa: F401

ratio = 1 / 0
