#!/usr/bin/env python3
"""Benchmark: the live endoscope_sim node (published rate and its CPU), not a test.

For each case (resolution, fps, ECM moving or still) it starts a private roscore, dvrk_sim with
``publish_tf`` (world -> ECM -> optical frames, the four tool frames; ``ecm/dwell`` 0 = the ECM
moves all the time, 1e6 = still) and ``endoscope.launch width height fps``, subscribes (AnyMsg:
no deserialisation in the benchmark) as ``--consumer`` says, and after ``--warmup`` s measures
for ``--duration`` s the message rate of each topic and the CPU of the endoscope_sim process
(% of one core, /proc). Consumers: ``viewer`` (default) = left/right ``image_raw`` and
``image_raw/compressed`` over TCP, as a separate viewer + recorder would (2 x 2.7 MB per frame
at 720p serialised, sent and read by this Python process, which competes for the same cores);
``recorder`` = ``image_raw/compressed`` and ``camera_info`` only, as in the platform, where the
raw images go zero-copy to the overlay nodelet in the same manager and the recorder takes the
compressed stream.
The simulator runs as its own process (nodelet standalone saras_simulation/EndoscopeSim).
Usage: endoscope_node.py [--duration S] [--warmup S] [--cases 720p30m,1080p30m,...] [--raw-only]
                         [--consumer viewer|recorder]
Case names: <height>p<fps><m|s> (m = ECM moving, s = still). Needs the workspace built
(scripts/env.sh: saras_drivers, saras_msgs; saras_collision for the bone boxes).
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time

from saras_simulation.bench_util import cpu_seconds, free_port, stop_process_groups

LAUNCH = """<launch>
  <group ns="/dvrk">
    <node pkg="saras_simulation" type="dvrk_sim" name="dvrk_sim">
      <rosparam command="load" file="$(find saras_simulation)/config/dvrk_sim.yaml"/>
      <param name="publish_tf" value="true"/>
      <param name="ecm/dwell" value="{dwell}"/>
      <param name="frames_file" value="{frames}"/>
    </node>
  </group>
  <include file="$(find saras_simulation)/launch/endoscope.launch">
    <arg name="width" value="{width}"/>
    <arg name="height" value="{height}"/>
    <arg name="fps" value="{fps}"/>
  </include>
</launch>
"""
FRAMES = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'saras_bringup',
                      'config', 'world_frames.yaml')
SIZES = {720: (1280, 720), 1080: (1920, 1080), 360: (640, 360)}


def find_pid(name, master_port):
    """pid of the process started with __name:=<name> under our private master."""
    for d in os.listdir('/proc'):
        if not d.isdigit():
            continue
        try:
            with open('/proc/%s/cmdline' % d, 'rb') as f:
                args = f.read().split(b'\0')
            with open('/proc/%s/environ' % d, 'rb') as f:
                env = f.read()
        except OSError:
            continue
        if ('__name:=%s' % name).encode() in args and (':%d' % master_port).encode() in env:
            return int(d)
    return None


def parse_case(c):
    p = c.index('p')
    return int(c[:p]), float(c[p + 1:-1]), c[-1] == 'm'


def run_case(height, fps, moving, renderer, args):
    import rospy
    from rospy.msg import AnyMsg
    width, height = SIZES[height]
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI='http://127.0.0.1:%d' % port)
    os.environ['ROS_MASTER_URI'] = env['ROS_MASTER_URI']
    procs = []
    fd, path = tempfile.mkstemp(suffix='.launch')
    with os.fdopen(fd, 'w') as f:
        f.write(LAUNCH.format(width=width, height=height, fps=fps, dwell=0.0 if moving else 1e6,
                              frames=os.path.normpath(FRAMES), renderer=renderer))
    try:
        procs.append(subprocess.Popen(['roscore', '-p', str(port)], env=env, preexec_fn=os.setsid,
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        time.sleep(2.0)
        procs.append(subprocess.Popen(['roslaunch', '--wait', path], env=env, preexec_fn=os.setsid,
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        rospy.init_node('endoscope_node_bench', anonymous=True, disable_signals=True)
        counts = {}
        if args.consumer == 'recorder':
            topics = ['/endoscope/%s/%s' % (e, t) for t in ('image_raw/compressed', 'camera_info')
                      for e in ('left', 'right')]
        else:
            topics = ['/endoscope/%s/image_raw' % e for e in ('left', 'right')]
            if not args.raw_only:
                topics += ['/endoscope/%s/image_raw/compressed' % e for e in ('left', 'right')]

        def cb(_msg, t):
            counts[t] = counts.get(t, 0) + 1
        subs = [rospy.Subscriber(t, AnyMsg, cb, callback_args=t, queue_size=2, buff_size=1 << 25)
                for t in topics]
        t_end = time.time() + 30.0
        pid = None
        while time.time() < t_end and (pid is None or not counts):
            pid = pid or find_pid('endoscope_sim', port)
            time.sleep(0.2)
        time.sleep(args.warmup)
        load0 = os.getloadavg()[0]
        c0, n0, w0 = cpu_seconds(pid) if pid else None, dict(counts), time.time()
        time.sleep(args.duration)
        c1, n1, w1 = cpu_seconds(pid) if pid else None, dict(counts), time.time()
        load1 = os.getloadavg()[0]
        for s in subs:
            s.unregister()
        dt = w1 - w0
        rates = [(n1.get(t, 0) - n0.get(t, 0)) / dt for t in topics]
        cpu = 100.0 * (c1 - c0) / dt if (c0 is not None and c1 is not None) else float('nan')
        return rates, cpu, load0, load1
    finally:
        stop_process_groups(procs, timeout=10.0)
        os.unlink(path)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--duration', type=float, default=10.0)
    ap.add_argument('--warmup', type=float, default=3.0)
    ap.add_argument('--cases', default='720p30m,720p30s,1080p30m,1080p30s,720p60m,720p60s,1080p60m,1080p60s')
    ap.add_argument('--renderers', default='cpp')
    ap.add_argument('--raw-only', action='store_true', help='no compressed subscribers (viewer)')
    ap.add_argument('--consumer', choices=('viewer', 'recorder'), default='viewer',
                    help='viewer: raw + compressed over TCP; recorder: compressed + camera_info only')
    args = ap.parse_args()
    rows = []
    for c, renderer in [(c, rd) for c in args.cases.split(',') for rd in args.renderers.split(',')]:
        height, fps, moving = parse_case(c)
        # rospy allows one init_node per process: every case runs in a child process
        r, w = os.pipe()
        pid = os.fork()
        if pid == 0:
            os.close(r)
            try:
                res = run_case(height, fps, moving, renderer, args)
                os.write(w, repr(res).encode())
            finally:
                os._exit(0)
        os.close(w)
        data = b''
        while True:
            chunk = os.read(r, 4096)
            if not chunk:
                break
            data += chunk
        os.waitpid(pid, 0)
        if not data:
            print('case %s %s failed' % (c, renderer), file=sys.stderr)
            continue
        rates, cpu, l0, l1 = eval(data.decode(), {'nan': float('nan'), 'inf': float('inf')})  # our own repr
        rows.append((c, renderer, SIZES[height], fps, moving, rates, cpu, l0, l1))
        print('done %s %s' % (c, renderer), file=sys.stderr)
    recorder = args.consumer == 'recorder'
    first, second = ('compressed', 'camera_info') if recorder else ('image_raw', 'compressed')
    print('\n| renderer | case | ECM | target fps | %s L / R [Hz] | %s L / R [Hz] | '
          'endoscope_sim CPU [%% of one core] | CPU per stereo frame [ms] | load avg before -> after |'
          % (first, second))
    print('|---|---|---|---|---|---|---|---|---|')
    for c, renderer, (w, h), fps, moving, rates, cpu, l0, l1 in rows:
        comp = '%.1f / %.1f' % (rates[2], rates[3]) if len(rates) > 2 else '-'
        per_frame = 10.0 * cpu / rates[0] if rates[0] > 0 else float('nan')
        print('| %s | %dx%d | %s | %g | %.1f / %.1f | %s | %.0f | %.1f | %.2f -> %.2f |' % (
            renderer, w, h, 'moving' if moving else 'still', fps, rates[0], rates[1], comp, cpu,
            per_frame, l0, l1))
    what = ('compressed and camera_info of both eyes (no raw subscriber: the recorder\'s view)' if recorder
            else 'image_raw and compressed of both eyes%s' % (' (raw only)' if args.raw_only else ''))
    print('\n%d s windows after %g s warm-up; subscribers (AnyMsg) take %s. CPU per stereo frame = '
          'node CPU time / left %s count (includes rendering, JPEG, publishing and the TF listener); '
          'the rate is CPU-bound when the host is loaded.' % (args.duration, args.warmup, what, first))


if __name__ == '__main__':
    main()
