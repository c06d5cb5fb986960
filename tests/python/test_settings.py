"""Every setting declared once: Python's attributes and keywords against the descriptions
(plydem.settings_reference(), the tables of docs/settings.md) and the command line's --help.

tests/test_settings.cpp checks the configs' keys and that each flag sets its field; this file checks
that each described setting is reachable from Python with the described default, and that `plydem
COMMAND --help` lists each flag with the same default.
"""
import json
import math
import os
import pathlib
import re
import subprocess

import pytest

import plydem

CLI = os.environ.get("PLYDEM_CLI", str(pathlib.Path(__file__).resolve().parents[2] / "build" / "plydem"))
SMALL = dict(length=1.0e-3, width=0.4e-3)
CLASSES = {"tension": plydem.TensionSettings, "strength": plydem.StrengthSettings}


def tables():
    return {t["id"]: t for t in plydem.settings_reference()}


def attribute(obj, dotted):
    for part in dotted.split("."):
        obj = getattr(obj, part)
    return obj


def set_attribute(obj, dotted, value):
    """obj.a.b = value, where obj.a is a copy (a struct): set on the copy, then write it back."""
    if "." not in dotted:
        setattr(obj, dotted, value)
        return
    head, rest = dotted.split(".", 1)
    part = getattr(obj, head)
    set_attribute(part, rest, value)
    setattr(obj, head, part)


def same_value(a, b):
    if isinstance(a, float) or isinstance(b, float):
        return a == b or (math.isnan(a) and math.isnan(b))
    return a == b


def help_defaults(command):
    """{flag: the default `plydem COMMAND --help` shows (None: none shown)}."""
    text = subprocess.run([CLI, command, "--help"], capture_output=True, text=True, check=True).stdout
    shown = {}
    for match in re.finditer(r"^\s*(--[\w-]+)(?:\s+(?:[A-Z]+(?::\{[^}]*\})?(?::[^\s\[]*)?))?(?:\s+\[([^\]]*)\])?",
                             text, re.MULTILINE):
        shown[match.group(1)] = match.group(2)
    return shown


def as_number(text):
    try:
        return float(text)
    except ValueError:
        return None


@pytest.mark.parametrize("command", ["tension", "strength"])
def test_every_setting_is_reachable_from_python_with_the_described_default(command):
    table = tables()[command]
    settings = CLASSES[command]()
    checked = 0
    for row in table["settings"]:
        if not row["python"]:
            assert row["no_python"], row["name"]
            continue
        value = attribute(settings, row["python"])
        if row["name"] == "material":
            assert value.name == row["default"]
        elif row["name"] == "layup":
            assert value == [] and row["default"] == ""
        elif row["name"] == "strategy_options":
            assert value == [] and row["default"] == []
        else:
            assert not row["python_native"], row["name"]
            assert same_value(value, row["default"]), (row["name"], value, row["default"])
        checked += 1
    assert checked >= 25


def sample(row):
    """A Python value other than the default."""
    default = row["default"]
    if row["choices"]:
        return next(c for c in row["choices"] if c != default and c != "petsc")
    if row["type"] == "switch":
        return not default
    if row["type"] == "integer":
        value = default + 1
        return int(row["min"]) if row["max"] is not None and value > row["max"] else value
    if row["type"] == "number":
        return 8.0 if default is None else default * 0.5 + 0.125
    return default + "x"


@pytest.mark.parametrize("command", ["tension", "strength"])
def test_every_python_attribute_takes_a_value(command):
    for row in tables()[command]["settings"]:
        if not row["python"] or row["python_native"]:
            continue
        settings = CLASSES[command]()
        value = sample(row)
        set_attribute(settings, row["python"], value)
        assert same_value(attribute(settings, row["python"]), value), row["name"]
        if "." not in row["python"]:  # a keyword of the constructor too
            assert same_value(getattr(CLASSES[command](**{row["python"]: value}), row["python"]), value)


@pytest.mark.parametrize("command", ["tension", "strength"])
def test_every_flag_is_in_the_help_with_the_described_default(command):
    shown = help_defaults(command)
    for row in tables()[command]["settings"]:
        if not row["flag"]:
            assert row["no_flag"], row["name"]
            continue
        assert row["flag"] in shown, row["flag"]
        default = shown[row["flag"]]
        if default is None or row["type"] == "switch":
            continue
        number = as_number(default)
        if number is not None and row["type"] in ("number", "integer"):
            assert number == pytest.approx(float(row["default_text"]), rel=1e-12, abs=0), row["flag"]
        else:
            assert default == row["default_text"], row["flag"]


def test_the_run_settings_are_keywords_of_the_tests():
    """threads (the new setting, declared once in the run's description) reaches Python, the command
    line and configs; results do not depend on it."""
    run = tables()["run"]
    assert {row["python"] for row in run["settings"]} == {"threads", "petsc_options"}
    coupon = plydem.CouponSpec(**SMALL)
    one = plydem.tension_test(coupon=coupon, threads=1)
    two = plydem.tension_test(coupon=coupon, threads=2)
    assert one["Ex"] == two["Ex"] and one["nu_xy"] == two["nu_xy"]
    with pytest.raises(plydem.Error, match="threads must be at least 0"):
        plydem.tension_test(coupon=coupon, threads=-1)
    with pytest.raises(TypeError, match="threads"):
        plydem.strength_test(coupon=coupon, threads="two")
    assert "--threads" in help_defaults("tension") and "--threads" in help_defaults("strength")
    cli = subprocess.run([CLI, "tension", "--threads", "-1"], capture_output=True, text=True)
    assert cli.returncode != 0 and "--threads" in cli.stderr


def test_drift_the_issue_named_is_gone():
    """linear_solver names petsc; backend offers backend_choices(); grips are one setting; the
    command line's --petsc-options and checkpoint flags reach Python."""
    for cls in CLASSES.values():
        assert "'petsc'" in cls.linear_solver.__doc__
        for name in ("checkpoint_every", "checkpoint", "restart", "edge_band_diameters"):
            assert hasattr(cls(), name), (cls.__name__, name)
    assert plydem.StrengthSettings(max_update_rank=50).max_update_rank == 50
    backends = next(r for r in tables()["tension"]["settings"] if r["name"] == "backend")["choices"]
    for name in backends:
        assert f"'{name}'" in plydem.TensionSettings.backend.__doc__
    with pytest.raises(plydem.Error, match='grips must be "free" or "clamped", got "loose"'):
        plydem.TensionSettings(grips="loose")
    s = plydem.StrengthSettings(checkpoint_every=5, checkpoint="state.ckpt", hole_diameter=0.2e-3)
    assert (s.checkpoint_every, s.checkpoint, s.hole_diameter) == (5, "state.ckpt", 0.2e-3)


def test_a_config_of_the_kind_tension_is_the_command(tmp_path):
    """The kind `tension` takes the command's settings as keys: the same test, the same numbers."""
    config = pathlib.Path(__file__).resolve().parents[1] / "data" / "tiny_tension.toml"
    subprocess.run([CLI, "run", str(config), "--out", str(tmp_path)], check=True, capture_output=True)
    rows = {}
    for line in (tmp_path / "results.csv").read_text().splitlines()[1:]:
        experiment, case, quantity, source, value, unit = line.split(",")
        rows[(quantity, source)] = float(value)
    expected = json.loads(subprocess.run(
        [CLI, "tension", "--json", "--strategy", "square", "--angle", "30", "--length-mm", "2",
         "--width-mm", "0.5"], check=True, capture_output=True, text=True).stdout)
    assert rows[("Ex", "dem square")] == pytest.approx(expected["Ex"] * 1e-9, rel=1e-9)
    assert rows[("nu_xy", "dem square")] == pytest.approx(expected["nu_xy"], rel=1e-9)
    assert rows[("Ex", "clt")] == pytest.approx(expected["theory"]["Ex"] * 1e-9, rel=1e-9)
    assert "1 OpenMP threads" in (tmp_path / "report.md").read_text()
