#!/usr/bin/env python3
"""Benchmark: CPU time per sample of the dVRK simulator's core, without ROS (not a test).

process_time() per ``ConsoleSim.step`` (the whole scripted da Vinci: surgeon script, five arms'
tracking steps and forward kinematics, teleoperation, pedals; config/dvrk_sim.yaml), best of
--repeat runs of --n consecutive 10 ms samples, and of the kinematics it is made of (PSM chain
forward pass with Jacobian, one tracking step). Waiting for a core is not counted, so the figures
hold on a loaded host better than the node's CPU share.
Usage: dvrk_sim_cpu.py [--n N] [--repeat R]   (other arguments of bench/run are ignored)
"""
import argparse
import os

os.environ.setdefault('OPENBLAS_NUM_THREADS', '1')   # as launch/dvrk.launch: 6x6 solves, no BLAS threads
import numpy as np  # noqa: E402
import yaml  # noqa: E402

from saras_simulation import dvrk_kinematics, dvrk_sim_core  # noqa: E402
from saras_simulation.bench_util import best_us  # noqa: E402

CONFIG = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'config', 'dvrk_sim.yaml')


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--n', type=int, default=500)
    ap.add_argument('--repeat', type=int, default=5)
    args, _ = ap.parse_known_args()
    n = args.n
    with open(CONFIG) as f:
        cfg = yaml.safe_load(f)
    sim = dvrk_sim_core.ConsoleSim(cfg)
    clock = [0.0]

    def steps():
        for _ in range(n):
            clock[0] += 0.01
            sim.step(clock[0])

    psm = dvrk_kinematics.psm_chain()
    q = np.array([0.1, -0.2, 0.12, 0.3, 0.2, -0.1])
    goal = psm.fk(q + 0.01)
    rows = [('ConsoleSim.step (one 100 Hz sample, 5 arms)', best_us(steps, n, args.repeat)),
            ('PSM Chain.fk with Jacobian', best_us(lambda: [psm.fk(q, jacobian=True) for _ in range(n)],
                                                   n, args.repeat)),
            ('PSM Chain.track (one tracking step)', best_us(lambda: [psm.track(goal, q) for _ in range(n)],
                                                            n, args.repeat))]
    print('dVRK simulator core, CPU per call, best of %d x %d' % (args.repeat, n))
    print('| operation | CPU [us] |')
    print('|---|---|')
    for name, us in rows:
        print('| %s | %.1f |' % (name, us))


if __name__ == '__main__':
    main()
