"""The paper's 0 deg comparison (Sec. 4): a hex2d E-glass lamina pulled along x and y, against CLT.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/zero_degree.py
"""
import plydem

result = plydem.tension_test(strategy="hex2d", coupon=plydem.CouponSpec(ply_angle=0.0))
for key, unit, scale in (("Ex", " GPa", 1e-9), ("Ey", " GPa", 1e-9), ("nu_xy", "", 1), ("nu_yx", "", 1)):
    dem, clt = result[key], result["theory"][key]
    print(f"{key} {dem * scale:.4g}{unit} (CLT {clt * scale:.4g}{unit}, {100 * (dem / clt - 1):+.2f}%)")
print(f"{result['particles']} particles, {result['bonds']} bonds")
