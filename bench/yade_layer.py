# The benchmark layer of bench/run in YADE: the same spheres as plydem's (read from the file
# plydem_kernel_bench writes: x y z radius per line), bonded where they touch by CohFrictMat
# cohesive contacts (normal, shear, bending and twisting moments, particles rotating), PFC-like
# local damping 0.7 in NewtonIntegrator. Prints one JSON line like plydem_kernel_bench.
# Run: yade -n -x -j THREADS bench/yade_layer.py LAYER_FILE STEPS THREADS
import json
import resource
import sys
import time

from yade import O, utils
from yade.wrapper import (Bo1_Sphere_Aabb, CohFrictMat, ForceResetter, Ig2_Sphere_Sphere_ScGeom6D,
                          InsertionSortCollider, InteractionLoop,
                          Ip2_CohFrictMat_CohFrictMat_CohFrictPhys,
                          Law2_ScGeom6D_CohFrictPhys_CohesionMoment, NewtonIntegrator)

layer_file, steps, threads = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
rows = [line.split() for line in open(layer_file) if line.strip() and not line.startswith('#')]

material = O.materials.append(
    CohFrictMat(young=20e9, poisson=0.3, density=2000, frictionAngle=0.5, isCohesive=True,
                normalCohesion=1e100, shearCohesion=1e100, momentRotationLaw=True,
                alphaKr=0.5, alphaKtw=0.5))
O.bodies.append([
    utils.sphere((float(x), float(y), float(z)), float(r), material=material, fixed=False)
    for x, y, z, r in rows
])
factor = 1.01  # touching neighbours only: the next shell is sqrt(3) diameters away
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb(aabbEnlargeFactor=factor)]),
    InteractionLoop([Ig2_Sphere_Sphere_ScGeom6D(interactionDetectionFactor=factor)],
                    [Ip2_CohFrictMat_CohFrictMat_CohFrictPhys(setCohesionNow=True,
                                                              setCohesionOnNewContacts=False)],
                    [Law2_ScGeom6D_CohFrictPhys_CohesionMoment(always_use_moment_law=True)]),
    NewtonIntegrator(damping=0.7, gravity=(0, 0, 0)),
]
O.dt = 0.5 * utils.PWaveTimeStep()
O.run(1, True)  # finds the contacts and makes them cohesive bonds (not timed)
bonds = O.interactions.countReal()
for b in O.bodies:
    b.state.vel = (1e-6 * ((b.id * 7919) % 13 - 6), 1e-6 * ((b.id * 104729) % 11 - 5), 0)
wall, cpu = time.time(), time.process_time()
O.run(steps, True)
wall, cpu = time.time() - wall, time.process_time() - cpu
particles = len(O.bodies)
print(json.dumps({
    "engine": "yade", "particles": particles, "bonds": bonds, "threads": threads,
    "steps": steps, "seconds": wall, "cpu_seconds": cpu,
    "ns_per_step": 1e9 * wall / steps,
    "particle_steps_per_s": particles * steps / wall,
    "bond_steps_per_s": bonds * steps / wall,
    "bytes_per_particle": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024.0 / particles,
    "memory_note": "peak resident memory of the whole yade process",
}))
