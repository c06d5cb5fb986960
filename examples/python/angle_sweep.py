"""Ex of a ply against its angle, 0 to 90 deg, beside classical lamination theory, as a plot.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/angle_sweep.py --out ex_sweep.png
    ... angle_sweep.py --strategy square --step 5 --out ex_square.png

Each angle is one `plydem tension` test (static solve, free grips) on the paper's coupon; the CLT
curve is the ply's off-axis modulus 1/S11-bar, drawn at every degree.
"""
import argparse
import math

import matplotlib

matplotlib.use("Agg")  # files only, no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import plydem  # noqa: E402

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--strategy", default="hex2d", help="registered strategy (default hex2d)")
parser.add_argument("--material", default="eglass-my750", help="built-in name or TOML file")
parser.add_argument("--step", type=float, default=15, help="angle step [deg]")
parser.add_argument("--length-mm", type=float, default=10.0, help="coupon length [mm]")
parser.add_argument("--width-mm", type=float, default=0.83, help="coupon width [mm]")
parser.add_argument("--out", default="ex_against_angle.png", help="the PNG to write")
args = parser.parse_args()

material = plydem.load_material(args.material)
angles = np.arange(0, 90 + 1e-9, args.step)
dem = []
for angle in angles:
    coupon = plydem.CouponSpec(material=material, ply_angle=math.radians(angle),
                               length=args.length_mm * 1e-3, width=args.width_mm * 1e-3)
    result = plydem.tension_test(strategy=args.strategy, coupon=coupon)
    dem.append(result["Ex"])
    print(f"{angle:5.1f} deg  Ex {result['Ex'] * 1e-9:8.4f} GPa  CLT "
          f"{result['theory']['Ex'] * 1e-9:8.4f} GPa  ({100 * (result['Ex'] / result['theory']['Ex'] - 1):+.2f}%)")

# CLT at every degree: Ex = 1 / S11-bar of the ply turned by the angle.
fine = np.linspace(0, 90, 91)
q = plydem.reduced_stiffness(material)
clt = [1 / np.linalg.inv(plydem.rotate_reduced_stiffness(q, math.radians(a)))[0, 0] for a in fine]

fig, ax = plt.subplots(figsize=(6, 4))
ax.plot(fine, np.array(clt) * 1e-9, "-", label="CLT")
ax.plot(angles, np.array(dem) * 1e-9, "o", label=f"DEM ({args.strategy})")
ax.set_xlabel("ply angle [deg]")
ax.set_ylabel("Ex [GPa]")
ax.set_title(f"{material.name}: Ex against ply angle")
ax.legend()
ax.grid(True, alpha=0.3)
fig.tight_layout()
fig.savefig(args.out, dpi=120)
print(f"wrote {args.out}")
