"""A packing strategy written in Python: a square layer turned with the fibre, eq. (33) springs.

The strategy, `py-square`, places particles on a square lattice whose axes lie along and across
the fibre, bonds each to its eight neighbours (families x, y, +45 and 135 deg of the lattice), and
gives every family the springs of the paper's eq. (33) in the corrected reading (ERRATA §2). In
its own frame the ply is orthotropic and all four families share one shear spring, so spinning
particles relax nothing: the model as simulated has the ply's stiffness exactly, which calibrate()
checks on the relaxed unit cell. Where eq. (33) gives a negative spring the strategy refuses (the
built-in `square` then finds the nearest non-negative springs).

Run it, or use it from the command line as a plug-in:

    PYTHONPATH=build/python /usr/bin/python3 examples/python/custom_packing.py
    build/plydem tension --plugin examples/python/custom_packing.py --strategy py-square --angle 30
"""
import math

import numpy as np

import plydem


def square_cell(spacing, lattice_angle, thickness):
    """The one-particle square cell, its families numbered x, y, +45, 135 deg of the lattice."""
    c, s = math.cos(lattice_angle), math.sin(lattice_angle)
    a1, a2 = spacing * np.array([c, s, 0.0]), spacing * np.array([-s, c, 0.0])
    return plydem.UnitCell(
        lattice_vectors=np.column_stack([a1, a2, [0.0, 0.0, thickness]]),
        basis=[np.zeros(3)], radius=[0.5 * spacing], volume=spacing**2 * thickness,
        bonds=[plydem.CellBond(0, 0, (1, 0, 0), 0), plydem.CellBond(0, 0, (0, 1, 0), 1),
               plydem.CellBond(0, 0, (1, 1, 0), 2), plydem.CellBond(0, 0, (-1, 1, 0), 3)],
        family_count=4)


class PySquare(plydem.Strategy):
    """Square layer along the fibre with eq. (33) springs (see the module's docstring)."""

    FAMILIES = ("x (fibre)", "y", "+45", "135")

    def __init__(self):
        plydem.Strategy.__init__(self)

    def description(self):
        return "square layer along the fibre, eq. (33) springs (a strategy written in Python)"

    def calibrate(self, material, ply_angle, thickness):
        target = plydem.rotate_reduced_stiffness(plydem.reduced_stiffness(material), ply_angle)
        q = plydem.reduced_stiffness(material)  # the ply in the lattice's frame: orthotropic
        d = thickness
        k_s = 2 * (q[2, 2] - q[0, 1]) * d / 3
        k_n = [(3 * q[0, 0] + q[0, 1] - 4 * q[2, 2]) * d / 3,
               (q[0, 1] + 3 * q[1, 1] - 4 * q[2, 2]) * d / 3,
               (q[0, 1] + 2 * q[2, 2]) * d / 3, (q[0, 1] + 2 * q[2, 2]) * d / 3]
        negative = [name for name, k in zip(("k_nx", "k_ny", "k_n+-"), k_n[:3]) if k < 0]
        if k_s < 0:
            negative.append("k_s (G12 < Q12)")
        if negative:
            raise plydem.Error(f"py-square: eq. (33) gives negative {', '.join(negative)} for "
                               f"{material.name}; the built-in strategy 'square' finds the "
                               "nearest non-negative springs")
        # Bending and twisting at unit spacing (bond radius 1/2): k_n R^2 / 4 and k_s R^2 / 2.
        springs = [plydem.FamilyStiffness(k, k_s, k / 16, k_s / 8) for k in k_n]
        offsets = (0.0, math.pi / 2, math.pi / 4, 3 * math.pi / 4)
        cell = square_cell(1.0, ply_angle, thickness)
        relaxed = plydem.in_plane_block(plydem.relaxed_stiffness(cell, springs))
        return plydem.Calibration(
            method="eq. (33), corrected reading, on a square lattice along the fibre",
            lattice_angle=ply_angle,
            families=[plydem.FamilyCalibration(label, ply_angle + offset, k)
                      for label, offset, k in zip(self.FAMILIES, offsets, springs)],
            target=target,
            affine=plydem.in_plane_block(plydem.affine_stiffness(cell, springs)),
            relaxed=relaxed,
            relaxed_error=plydem.relative_difference(relaxed, target))

    def assemble(self, coupon, calibration):
        spacing, r = coupon.particle_diameter, 0.5 * coupon.particle_diameter
        c, s = math.cos(calibration.lattice_angle), math.sin(calibration.lattice_angle)
        a1, a2 = spacing * np.array([c, s]), spacing * np.array([-s, c])
        # Lattice sites (origin at (r, r)) whose particles lie inside the rectangle.
        corners = np.array([[x, y] for x in (0, coupon.length) for y in (0, coupon.width)]) - r
        ij = np.linalg.solve(np.column_stack([a1, a2]), corners.T).T
        lo, hi = np.floor(ij.min(axis=0)) - 1, np.ceil(ij.max(axis=0)) + 1
        i, j = np.meshgrid(np.arange(lo[0], hi[0] + 1), np.arange(lo[1], hi[1] + 1), indexing="ij")
        i, j = i.ravel(), j.ravel()
        xy = r + np.outer(i, a1) + np.outer(j, a2)
        tol = 1e-9 * spacing
        keep = ((xy[:, 0] >= r - tol) & (xy[:, 0] <= coupon.length - r + tol) &
                (xy[:, 1] >= r - tol) & (xy[:, 1] <= coupon.width - r + tol))
        sites = {(int(a), int(b)): n for n, (a, b) in enumerate(zip(i[keep], j[keep]))}
        pairs, family = [], []
        for (a, b), n in sites.items():
            for f, (da, db) in enumerate(((1, 0), (0, 1), (1, 1), (-1, 1))):
                m = sites.get((a + da, b + db))
                if m is not None:
                    pairs.append((n, m))
                    family.append(f)
        position = np.zeros((len(sites), 3))
        position[:, :2] = xy[keep]
        model = plydem.assemble_specimen(
            position=position, radius=r, particle_volume=spacing**2 * coupon.thickness,
            density=coupon.material.density, pairs=np.array(pairs, dtype=np.int32).reshape(-1, 2),
            family=family, thickness=coupon.thickness,
            description=f"py-square layer, lattice at {math.degrees(calibration.lattice_angle):.4g}"
                        f" deg, {len(sites)} particles",
            families=calibration.families)
        if coupon.complete_boundary_cells:  # free edges carry their missing partners' share
            plydem.complete_boundary_cells(model, family_count=4, bulk_bonds=2)
        return model

    def boundary_completion(self):
        return plydem.BoundaryCompletion(family_count=4, bulk_bonds=2)

    def unit_cell(self, calibration, thickness):
        return square_cell(1.0, calibration.lattice_angle, thickness)


plydem.register_strategy("py-square", PySquare)

if __name__ == "__main__":
    for angle in (0, 30):
        coupon = plydem.CouponSpec(ply_angle=math.radians(angle))
        result = plydem.tension_test(strategy="py-square", coupon=coupon)
        builtin = plydem.tension_test(strategy="square", coupon=coupon)
        for key, unit, scale in (("Ex", "GPa", 1e-9), ("Ey", "GPa", 1e-9), ("nu_xy", "", 1)):
            dem, clt, ref = result[key], result["theory"][key], builtin[key]
            print(f"{angle:2d} deg {key:5s} py-square {dem * scale:8.4f} {unit:3s} CLT "
                  f"{clt * scale:8.4f} ({100 * (dem / clt - 1):+.2f}%)  built-in square "
                  f"{ref * scale:8.4f}")
