"""Runs an example script if the Python packages it needs are importable, else reports a skip.

    python3 run_example.py matplotlib examples/python/angle_sweep.py --step 30 ...

The first argument is a comma-separated list of modules; a missing one prints `SKIPPED: ...` and
exits 77, which ctest reports as skipped (SKIP_RETURN_CODE), not passed.
"""
import importlib.util
import runpy
import sys

modules, script, *args = sys.argv[1:]
missing = [m for m in modules.split(",") if importlib.util.find_spec(m) is None]
if missing:
    print(f"SKIPPED: {script} needs {', '.join(missing)} (scripts/setup installs python3-{missing[0]})")
    sys.exit(77)
sys.argv = [script, *args]
runpy.run_path(script, run_name="__main__")
