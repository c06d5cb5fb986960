"""The Python module (python/plydem_module.cpp) against the library and the command line.

ctest runs this with PYTHONPATH=<build>/python and PLYDEM_CLI=<build>/plydem (tests/CMakeLists.txt);
by hand: PYTHONPATH=build/python PLYDEM_CLI=build/plydem /usr/bin/python3 -m pytest tests/python
"""
import json
import math
import os
import pathlib
import re
import subprocess

import numpy as np
import pytest

import plydem

DATA = pathlib.Path(__file__).resolve().parent.parent / "data"
CLI = os.environ.get("PLYDEM_CLI", str(pathlib.Path(__file__).resolve().parents[2] / "build" / "plydem"))


def cli_json(*args):
    out = subprocess.run([CLI, "tension", "--json", *args], check=True, capture_output=True, text=True)
    return json.loads(out.stdout)


def assert_same(a, b, path="", rel=1e-12):
    """Equal JSON values, numbers to `rel` relative; timings (keys ending in 'seconds') skipped,
    and the command line's "provenance" (which plydem, which command) too."""
    if isinstance(a, dict):
        assert isinstance(b, dict), f"{path}: {b!r} is not an object"
        a = {k: v for k, v in a.items() if k != "provenance"}
        b = {k: v for k, v in b.items() if k != "provenance"}
        assert set(a) == set(b), f"{path}: keys {sorted(a)} vs {sorted(b)}"
        for key in a:
            if not key.endswith("seconds"):
                assert_same(a[key], b[key], f"{path}.{key}", rel)
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), f"{path}: lengths differ"
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{path}[{i}]", rel)
    elif isinstance(a, (int, float)) and not isinstance(a, bool):
        assert isinstance(b, (int, float)), f"{path}: {a!r} vs {b!r}"
        assert b == pytest.approx(a, rel=rel, abs=1e-300), f"{path}: {a!r} vs {b!r}"
    else:
        assert a == b, f"{path}: {a!r} vs {b!r}"


def count_numbers(value):
    if isinstance(value, dict):
        return sum(count_numbers(v) for k, v in value.items() if not k.endswith("seconds"))
    if isinstance(value, list):
        return sum(count_numbers(v) for v in value)
    return 1 if isinstance(value, (int, float)) and not isinstance(value, bool) else 0


def test_tension_default_equals_cli_json():
    """The paper's 0 deg lamina (the default job): the same dict as `plydem tension --json`."""
    expected = cli_json()
    got = plydem.tension_test()
    assert count_numbers(expected) > 10
    assert_same(expected, got)
    assert got["Ex"] == pytest.approx(got["theory"]["Ex"], rel=0.05)


def test_tension_keywords_equal_cli_json():
    """A 30 deg square-packing coupon set up by keywords, against the same flags."""
    expected = cli_json("--strategy", "square", "--angle", "30", "--length-mm", "2", "--width-mm", "0.5")
    coupon = plydem.CouponSpec(ply_angle=30 * math.pi / 180, length=2e-3, width=0.5e-3)
    got = plydem.tension_test(plydem.TensionSettings(strategy="square", coupon=coupon))
    assert_same(expected, got)
    assert got["Ex"] != expected["Ex"] * 1.001  # a number, compared above


def test_tension_json_mismatch_is_seen():
    """The comparison above can fail: a different angle gives a different dict."""
    coupon = plydem.CouponSpec(ply_angle=31 * math.pi / 180, length=2e-3, width=0.5e-3)
    got = plydem.tension_test(strategy="square", coupon=coupon)
    expected = cli_json("--strategy", "square", "--angle", "30", "--length-mm", "2", "--width-mm", "0.5")
    with pytest.raises(AssertionError):
        assert_same(expected, got)


def test_materials():
    assert "eglass-my750" in plydem.builtin_materials()
    eglass = plydem.load_material("eglass-my750")
    assert eglass.E1 > eglass.E2 > 0
    mine = plydem.Material(name="mine", E1=eglass.E1, E2=eglass.E2, G12=eglass.G12, nu12=eglass.nu12,
                           nu23=eglass.nu23)
    assert mine.nu21 == pytest.approx(eglass.nu21, rel=1e-15)
    with pytest.raises(TypeError, match="E4"):
        plydem.Material(E4=1.0)


def test_registry_and_calibration():
    names = plydem.strategies()
    assert {"hex2d", "square", "hcp", "lattice"} <= set(names)
    hcp = plydem.create_strategy("hcp")
    assert isinstance(hcp.options(), dict) and hcp.option_list()
    name = next(iter(hcp.options()))
    hcp.set_option(name, hcp.options()[name])
    c = plydem.create_strategy("hex2d").calibrate(plydem.load_material("eglass-my750"), 0.0, 0.2e-3)
    for key in ("target", "affine", "relaxed"):
        assert isinstance(c[key], np.ndarray) and c[key].shape == (3, 3)
    assert np.allclose(c["relaxed"], c["target"], rtol=0, atol=1e-6 * np.abs(c["target"]).max())
    assert c["families"] and c["families"][0]["normal"] > 0


def grip_coupon():
    model = plydem.create_strategy("hex2d").build(plydem.CouponSpec(length=2e-3, width=0.5e-3))
    p = model.particles
    x = p.reference_position[:, 0]
    p.group[x < x.min() + 0.1e-3] = plydem.LEFT_GRIP
    p.group[x > x.max() - 0.1e-3] = plydem.RIGHT_GRIP
    return model


def test_views_see_the_static_solution_without_a_copy():
    model = grip_coupon()
    p = model.particles
    u = p.displacement  # taken before the solve
    assert u.shape == (len(p), 3) and not u.any()
    constraints = plydem.DofConstraints(len(p))
    assert constraints.fix_group(model, plydem.LEFT_GRIP, plydem.UX, 0.0) > 0
    assert constraints.fix_group(model, plydem.RIGHT_GRIP, plydem.UX, 2e-6) > 0
    result = plydem.solve_static(model, constraints, pin_rigid_modes=True)
    assert result["strain_energy"] > 0
    assert u[:, 0].max() == pytest.approx(2e-6, rel=1e-12)  # the old view sees the solution
    assert np.shares_memory(u, p.displacement)
    assert u.ctypes.data == p.displacement.ctypes.data
    # Writing through a view reaches the C++ array.
    p.displacement[0, 2] = 1.25
    assert model.particles.displacement[0, 2] == 1.25
    # The grips' reactions balance.
    assert result["reaction"][:, 0].sum() == pytest.approx(0.0, abs=1e-9 * abs(result["reaction"][:, 0]).max())


def test_invariant_arrays_are_read_only():
    model = grip_coupon()
    for array in (model.bonds.first, model.bonds.second, model.bonds.length, model.particles.reference_position,
                  model.particles.mass):
        with pytest.raises(ValueError):
            array[0] = 0
    model.bonds.normal_stiffness[0] *= 1.0  # stiffnesses are writable
    first = model.bonds.first
    del model  # the view keeps the model alive
    assert first.min() >= 0


def test_laminate_and_vtu(tmp_path):
    model = plydem.build_laminate(plydem.create_strategy("hex2d"), plydem.CouponSpec(length=1e-3, width=0.3e-3),
                                  "[0/90]")
    assert set(np.unique(model.particles.ply)) == {0, 1}
    assert (model.bonds.kind == 1).any()
    plydem.write_vtu(model, str(tmp_path / "p.vtu"), str(tmp_path / "b.vtu"))
    assert "UnstructuredGrid" in (tmp_path / "b.vtu").read_text()


def test_errors_are_plydem_error_with_the_library_message():
    with pytest.raises(plydem.Error, match="unknown strategy 'nosuch'.*hex2d"):
        plydem.create_strategy("nosuch")
    with pytest.raises(plydem.Error, match="not positive definite"):
        plydem.load_material(str(DATA / "not_positive_definite.toml"))
    with pytest.raises(plydem.Error, match="not positive definite"):
        plydem.Material(name="bad", E1=16.2e9, E2=16.2e9, G12=5.83e9, nu12=0.9, nu23=0.4)
    with pytest.raises(plydem.Error, match="no option 'nosuch'"):
        plydem.create_strategy("hex2d", nosuch=1)
    with pytest.raises(plydem.Error, match="length must be positive"):
        plydem.CouponSpec(length=0)
    with pytest.raises(plydem.Error, match="unknown strategy 'nosuch'"):
        plydem.tension_test(strategy="nosuch")
    assert issubclass(plydem.Error, RuntimeError)


def test_explicit_run_calls_back_every_n_cycles_and_stops_on_false():
    model = grip_coupon()
    integrator = plydem.ExplicitIntegrator(model)
    assert integrator.time_step > 0
    v = 1e-3  # m/s per grip
    integrator.set_prescribed_motions([
        plydem.PrescribedMotion(group=plydem.LEFT_GRIP, velocity=(-v, 0, 0), fix_velocity=(True, False, False)),
        plydem.PrescribedMotion(group=plydem.RIGHT_GRIP, velocity=(v, 0, 0), fix_velocity=(True, False, False)),
    ])
    u = model.particles.displacement
    seen = []

    def callback(check):
        integrator.gather()  # the views show the kernel's state from here
        seen.append((check["run_cycles"], float(u[:, 0].max())))
        return len(seen) < 3

    report = integrator.run(max_cycles=10_000, check_interval=200, callback=callback)
    assert report["stop"] == "hook" and report["cycles"] == 600 and report["checks"] == 3
    assert [c for c, _ in seen] == [200, 400, 600]
    # The right grip moved v dt per cycle, seen through the same view.
    for cycles, umax in seen:
        assert umax == pytest.approx(v * integrator.time_step * cycles, rel=1e-9)
    assert integrator.cycles == 600
    assert integrator.run(max_cycles=100)["stop"] == "cycle limit"


def test_an_exception_in_the_callback_ends_the_run():
    model = grip_coupon()
    integrator = plydem.ExplicitIntegrator(model)

    def callback(check):
        raise KeyError("stop here")

    with pytest.raises(KeyError, match="stop here"):
        integrator.run(max_cycles=1000, check_interval=100, callback=callback)
    assert integrator.cycles == 100
    with pytest.raises(plydem.Error):
        integrator.run()  # no stop condition


def test_ctrl_c_stops_an_explicit_run():
    import signal
    import sys
    import time

    script = (
        "import plydem, sys\n"
        "m = plydem.create_strategy('hex2d').build(plydem.CouponSpec(length=2e-3, width=0.5e-3))\n"
        "g = plydem.ExplicitIntegrator(m)\n"
        "print('running', flush=True)\n"
        "try:\n"
        "    g.run(max_cycles=10**12, check_interval=1000)\n"
        "except KeyboardInterrupt:\n"
        "    print('interrupted after', g.cycles, flush=True)\n"
        "    sys.exit(3)\n"
    )
    child = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True,
                             env=dict(os.environ))
    assert child.stdout.readline().strip() == "running"
    time.sleep(0.5)
    child.send_signal(signal.SIGINT)
    out, _ = child.communicate(timeout=60)
    assert child.returncode == 3, out
    assert "interrupted after" in out


def test_docstrings_on_everything():
    def described(name, doc):
        lines = [line for line in (doc or "").strip().splitlines()
                 if line.strip() and not line.strip().startswith(name + "(")]
        return bool(lines)

    missing = []
    for name, obj in vars(plydem).items():
        if name.startswith("_") or isinstance(obj, (int, str)):
            continue
        if not described(name, obj.__doc__):
            missing.append(name)
        if isinstance(obj, type) and obj.__module__ == "plydem":
            for attr, member in vars(obj).items():
                if (not attr.startswith("_") or attr == "__init__") and not described(attr, member.__doc__):
                    missing.append(f"{name}.{attr}")
    assert not missing



def cli_run(*args):
    return subprocess.run([CLI, *args], capture_output=True, text=True)


def test_linear_solvers_are_the_cli_ones():
    """linear_solver takes what `plydem tension --linear-solver` takes (the same parser) and names it."""
    help_text = " ".join(cli_run("tension", "--help").stdout.split())
    for cls in (plydem.TensionSettings, plydem.StrengthSettings):
        doc = cls.linear_solver.__doc__
        for name in ("auto", "direct", "cholmod", "petsc"):
            assert f"{name} (" in help_text and f"'{name}'" in doc, (cls.__name__, name)
            try:
                assert cls(linear_solver=name).linear_solver == name
            except plydem.Error as error:  # a build without PETSc says so, as the CLI does
                assert name == "petsc" and "built without PETSc" in str(error)
        with pytest.raises(plydem.Error) as error:
            cls(linear_solver="nosuch")
        cli = cli_run("tension", "--linear-solver", "nosuch")
        assert cli.returncode != 0 and str(error.value) in cli.stderr


def test_backends_are_the_cli_ones():
    """backend takes and names the values `plydem tension --backend` offers, nothing else."""
    offered = re.search(r"--backend TEXT:\{([^}]*)\}", cli_run("tension", "--help").stdout)
    assert offered and offered.group(1).split(",") == ["cpu", "cuda", "emulation", "reference"]
    model = grip_coupon()
    for name in offered.group(1).split(","):
        assert f"'{name}'" in plydem.TensionSettings.backend.__doc__
        assert f"'{name}'" in plydem.ExplicitIntegrator.__init__.__doc__
        assert plydem.TensionSettings(backend=name).backend == name
    assert plydem.TensionSettings().backend == "cpu"
    assert plydem.ExplicitIntegrator(model, backend="cpu").time_step > 0
    for name in ("gpu", "fused"):
        assert cli_run("tension", "--solver", "explicit", "--backend", name).returncode != 0
        choices = "cpu, cuda, emulation, reference"
        with pytest.raises(plydem.Error, match=f"unknown backend '{name}': {choices}"):
            plydem.TensionSettings(backend=name)
        with pytest.raises(plydem.Error, match=f"unknown backend '{name}': {choices}"):
            plydem.ExplicitIntegrator(model, backend=name)

def test_interface_mixed_mode_settings_and_bond_fields():
    settings = plydem.StrengthSettings(interface_GIc=300.0, interface_bk_exponent=1.5)
    assert settings.interface_bk_exponent == 1.5
    assert plydem.StrengthSettings().interface_bk_exponent == pytest.approx(2.284)
    model = plydem.build_laminate(plydem.create_strategy("hex2d"), plydem.CouponSpec(length=1e-3, width=0.3e-3),
                                  "[0/90]")
    # In-ply and unassigned interface bonds keep PFC's law (exponent 0); the law's fields are writable.
    assert (model.bonds.mixed_mode_exponent == 0).all()
    assert (model.bonds.fracture_energy_ratio == 1).all() and (model.bonds.peak_energy_ratio == 1).all()
    model.bonds.mixed_mode_exponent[0] = 2.0
