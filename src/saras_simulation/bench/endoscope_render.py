#!/usr/bin/env python3
"""Benchmark of the stereo endoscope renderers (endoscope_sim's per-frame work), 1 process.

First the compiled core (the ``endoscope_render`` CLI of saras_drivers_endoscope_core, the
default renderer of endoscope_sim) if it is built: one eye, ECM viewpoint of the platform with
the 13 pelvic-bone boxes and 2 shafts, or the tissue alone, moving (static layer re-rendered
every frame) and still; process CPU per frame and the thread CPU of each stage (tissue solve,
colour, bones, copy, shafts). Then the Python reference renderer:

For each resolution: time per stereo frame (left + right) when the camera is still (cached
static layer + 4 instrument shafts; the usual case, the ECM moves now and then) and when it
moves (static layer re-rendered every frame), one eye after the other and in two threads as
endoscope_sim does, plus the publishing costs (Image bytes copy, JPEG encode at quality 85 and
75 for image_raw/compressed). CPU = process CPU time per pair (all threads).
Usage: endoscope_render.py [--frames N] [--cpp-only]
"""
import argparse
import os
import re
import subprocess
import time
from concurrent.futures import ThreadPoolExecutor

import cv2
import numpy as np

from saras_simulation.bench_util import find_devel_executable
from saras_simulation import dvrk_motion as dm
from saras_drivers import endoscope_renderer as er
from saras_simulation import rigid
from saras_simulation.tissue_surface import TissueSurface

CFG = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'config')


def measure(fn, n):
    fn(0)
    w0, c0 = time.perf_counter(), time.process_time()
    for i in range(n):
        fn(i + 1)
    w, c = time.perf_counter() - w0, time.process_time() - c0
    return w / n, c / n


def find_cli():
    return find_devel_executable('endoscope_render')


def bench_cpp(frames):
    """Table of the C++ core (endoscope_render --frames N), one eye."""
    cli = find_cli()
    if cli is None:
        print('endoscope_render (C++ core) not built: skipped')
        return
    pose = '0.08338741 0.0001007 0.17004034 -0.94724192 0.00053920 0.32051871 0.00039718'  # platform ECM view
    pelvis = os.path.join(CFG, '..', '..', 'saras_collision', 'config', 'pelvis_vertices.txt')
    shafts = ['0.0258 -0.0335 0.0957 0.1 -0.08 0.22 0.004', '0.03 0.035 0.095 0.10 0.08 0.22 0.004']
    print('C++ core (endoscope_render), one eye, %d frames per case, load average: %s' % (
        frames, ' '.join('%.2f' % v for v in os.getloadavg())))
    print('| resolution | scene | ECM | CPU per eye [ms] | tissue | colour | bones | copy | shafts |')
    print('|---|---|---|---|---|---|---|---|---|')
    for (w, h) in ((1280, 720), (1920, 1080)):
        for scene in ('tissue', 'bones'):
            if scene == 'bones' and not os.path.isfile(pelvis):
                continue
            for moving in (True, False):
                cmd = [cli, '--camera-info', os.path.join(CFG, 'endoscope_left.yaml'), '--width', str(w),
                       '--height', str(h), '--pose', pose, '--frames', str(frames)]
                for sh in shafts:
                    cmd += ['--shaft', sh]
                if scene == 'bones':  # bones_marker_frame 10 cm above world, in view of the ECM
                    cmd += ['--boxes', pelvis, '--boxes-pose', '-0.02 0 0.1 0 0 0 1']
                if moving:
                    cmd.append('--moving')
                out = subprocess.run(cmd, check=True, stdout=subprocess.PIPE, universal_newlines=True).stdout
                cpu = float(re.search(r'([0-9.]+) ms/frame CPU', out).group(1))
                st = dict((k, float(v)) for k, v in re.findall(r'(\w+) ([0-9.e+-]+)', out.split('stages')[1]))
                print('| %dx%d | %s | %s | %.1f | %.1f | %.1f | %.1f | %.2f | %.2f |' % (
                    w, h, scene, 'moving' if moving else 'still', cpu, st['tissue'], st['colour'], st['boxes'],
                    st['copy'], st['shafts']))
    print('(stage columns: thread CPU ms per frame; a still camera re-uses the cached static layer)\n')


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--frames', type=int, default=20)
    ap.add_argument('--cpp-only', action='store_true', help='only the C++ core table')
    args = ap.parse_args()
    bench_cpp(max(args.frames, 50))
    if args.cpp_only:
        return
    kin = dm.StandInKinematics()
    T_ecm = rigid.make_transform(t=[0.14, 0.0, 0.24])
    yaw, pitch = dm.direction_to_yaw_pitch([-0.13, 0.0, -0.17])
    tools = [(np.array([0.03, -0.03, 0.09]), np.array([0.10, -0.08, 0.22]), 0.004),
             (np.array([0.03, 0.035, 0.095]), np.array([0.10, 0.08, 0.22]), 0.004),
             (np.array([0.0, 0.05, 0.075]), np.array([0.02, 0.13, 0.20]), 0.0025),
             (np.array([0.0, -0.05, 0.075]), np.array([0.02, -0.13, 0.20]), 0.0025)]
    # The platform's pelvic-bone boxes (saras_collision, bones_marker_frame = world + 0.10 z)
    # when present, else two stand-in boxes.
    pelvis = os.path.join(CFG, '..', '..', 'saras_collision', 'config', 'pelvis_vertices.txt')
    if os.path.isfile(pelvis):
        boxes = [b + [0.0, 0.0, 0.10] for b in er.load_boxes(pelvis)]
    else:
        boxes = [np.array([[x, y, z] for x in (a, a + 0.03) for y in (b, b + 0.02) for z in (0.10, 0.13)])
                 for a, b in ((-0.05, 0.03), (-0.05, -0.05))]
    rows = []
    print('cv2 threads: %d, cpus: %d, load average: %s, bone boxes: %d' % (
        cv2.getNumThreads(), os.cpu_count(), ' '.join('%.2f' % v for v in os.getloadavg()), len(boxes)))
    for (w, h) in ((1280, 720), (1920, 1080)):
        base = er.CameraModel.from_yaml_file(os.path.join(CFG, 'endoscope_left.yaml')).scaled(w, h)
        t0 = time.perf_counter()
        rend = {eye: er.SceneRenderer(base, TissueSurface(), boxes=boxes) for eye in ('left', 'right')}
        setup = time.perf_counter() - t0

        def pose(eye, i, moving):
            q = [yaw + (0.002 * i if moving else 0.0), pitch, 0.09, 0.0]
            return T_ecm @ kin.ecm_tip_in_base(q) @ kin.camera_in_tip(eye)
        out = {}

        def frame(i, moving):
            for eye in ('left', 'right'):
                out[eye] = rend[eye].render(pose(eye, i, moving), tools, out=out.get(eye))
        pool = ThreadPoolExecutor(max_workers=2)

        def frame_parallel(i):   # as endoscope_sim (parallel_eyes: true)
            jobs = {eye: pool.submit(rend[eye].render, pose(eye, i, True), tools, out.get(eye))
                    for eye in ('left', 'right')}
            for eye, j in jobs.items():
                out[eye] = j.result()
        still = measure(lambda i: frame(i, False), args.frames)
        moving = measure(lambda i: frame(i, True), max(3, args.frames // 2))
        moving2 = measure(lambda i: frame_parallel(i + 1000), max(3, args.frames // 2))
        pool.shutdown()
        img = out['left']
        tobytes = measure(lambda i: [img.tobytes() for _ in range(2)], args.frames)
        jpeg = measure(lambda i: [cv2.imencode('.jpg', img, [cv2.IMWRITE_JPEG_QUALITY, 85])
                                  for _ in range(2)], max(3, args.frames // 2))
        jpeg75 = measure(lambda i: [cv2.imencode('.jpg', img, [cv2.IMWRITE_JPEG_QUALITY, 75])
                                    for _ in range(2)], max(3, args.frames // 2))
        rows.append((w, h, setup, still, moving, moving2, tobytes, jpeg, jpeg75))
    print()
    print('%-10s %7s | %-26s | %-26s | %-26s | %-8s | %-8s | %-8s' % (
        'resolution', 'setup s', 'still: wall ms (fps), CPU', 'moving: wall ms (fps), CPU',
        'moving 2 threads', 'raw x2', 'jpeg85x2', 'jpeg75x2'))
    for w, h, setup, still, moving, moving2, tob, jpg, jpg75 in rows:
        cell = lambda m: '%6.1f (%5.1f fps) %6.1f' % (m[0] * 1e3, 1.0 / m[0], m[1] * 1e3)  # noqa: E731
        print('%4dx%-5d %7.2f | %s | %s | %s | %5.2f ms | %5.1f ms | %5.1f ms' % (
            w, h, setup, cell(still), cell(moving), cell(moving2), tob[0] * 1e3, jpg[0] * 1e3,
            jpg75[0] * 1e3))
    print('\nTimes per stereo pair (left + right), ms. CPU = process CPU time per pair, ms (all threads).')
    print('load average after: %s' % ' '.join('%.2f' % v for v in os.getloadavg()))
    print('\nstill = ECM at rest (static layer cached); moving = ECM moving every frame.')
    print('Excludes ROS serialisation/transport of the 2.7 MB (720p) / 6.2 MB (1080p) images.')


if __name__ == '__main__':
    main()
