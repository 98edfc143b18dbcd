"""Prints a table of the cost of the kinematics functions and of URDF generation.

Each row: median over 5 repetitions of the mean time per call of N calls (random inputs
within the joint limits, generated beforehand), on one core.
"""
import statistics
import subprocess
import sys
import time
import os

import numpy as np

from saras_description import config as cfg
from saras_description import kinematics as k
from saras_description import urdf


def bench(fn, inputs, repeat=5):
    per_call = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for x in inputs:
            fn(x)
        per_call.append((time.perf_counter() - t0) / len(inputs))
    return statistics.median(per_call)


def rand(limits, rng, n):
    lo = np.array([lim.lower for lim in limits.values()])
    hi = np.array([lim.upper for lim in limits.values()])
    return [rng.uniform(lo, hi) for _ in range(n)]


def main():
    rng = np.random.default_rng(0)
    n = 2000
    he = cfg.load_hand_eye()
    saras = rand(k.saras_arm_joint_limits(), rng, n)
    psm = rand(k.psm_joint_limits(), rng, n)
    ecm = rand(k.ecm_joint_limits(), rng, n)
    touch = rand(k.touch_joint_limits(), rng, n)
    tips = [k.saras_arm_tip_in_rcm(q[7:])[:3, 3] for q in saras]
    rows = [
        ('saras_arm_tip_in_base (13 joints)', bench(k.saras_arm_tip_in_base, saras)),
        ('saras_arm_rcm_in_base (7 PA joints)', bench(lambda q: k.saras_arm_rcm_in_base(q[:7]), saras)),
        ('saras_arm_tip_in_rcm (ER + adapter)', bench(lambda q: k.saras_arm_tip_in_rcm(q[7:]), saras)),
        ('saras_arm_ik_tip', bench(k.saras_arm_ik_tip, tips)),
        ('psm_tip_in_base', bench(k.psm_tip_in_base, psm)),
        ('psm_ik_position', bench(lambda q: k.psm_ik_position(q[:3]), psm)),
        ('ecm_camera_poses', bench(lambda q: k.ecm_camera_poses(q, he), ecm)),
        ('touch_handle_in_base', bench(k.touch_handle_in_base, touch)),
    ]
    setups = cfg.load_saras_arms()
    gen = [
        ('URDF saras_arm (generate + serialise)', bench(
            lambda _: urdf.saras_arm_urdf('mesa_left/', setups['mesa_left']).to_string(), range(20))),
        ('URDF platform (generate + serialise)', bench(lambda _: urdf.platform_urdf().to_string(), range(20))),
    ]
    make_urdf = os.path.join(os.path.dirname(__file__), '..', 'scripts', 'make_urdf')
    t0 = time.perf_counter()
    for _ in range(5):
        subprocess.run([sys.executable, make_urdf, 'saras_arm', '--prefix', 'mesa_left/'], check=True,
                       stdout=subprocess.DEVNULL)
    cli = (time.perf_counter() - t0) / 5
    print('saras_description benchmark (python %s, numpy %s, %d random inputs per row)'
          % (sys.version.split()[0], np.__version__, n))
    print('| function | time per call [us] | calls/s |')
    print('|---|---:|---:|')
    for name, t in rows:
        print('| %s | %.1f | %.0f |' % (name, t * 1e6, 1.0 / t))
    print('| %s | %.1f | %.0f |' % ('make_urdf saras_arm (process, incl. python start-up)', cli * 1e6, 1.0 / cli))
    for name, t in gen:
        print('| %s | %.1f | %.0f |' % (name, t * 1e6, 1.0 / t))


if __name__ == '__main__':
    main()
