"""Helpers of the tests that run scripts/cluster/netns.sh (a deployment under a test prefix)."""
import os
import subprocess
import time
from pathlib import Path

import pytest

WS = Path(__file__).resolve().parents[3]
NETNS = WS / 'scripts' / 'cluster' / 'netns.sh'
ROLES = ['core_pc', 'teleop_pc', 'dvrk_pc', 'console_pc', 'saras_left', 'saras_right']


class Deployment:
    """netns.sh with its own prefix, subnet a.b.c.0/24, roles and run directory."""

    def __init__(self, prefix, base, roles=ROLES):
        self.prefix, self.base, self.roles = prefix, base, list(roles)
        self.run_dir = '/tmp/%s_cluster' % prefix
        self.addr = {role: '%s.%d' % (base, 10 + i) for i, role in enumerate(self.roles)}
        self.env = dict(os.environ, SARAS_NETNS_PREFIX=prefix, SARAS_NETNS_SUBNET=base + '.0/24',
                        SARAS_NETNS_RUN=self.run_dir, SARAS_NETNS_ROLES=' '.join(self.roles))

    def netns(self, *args, timeout=60, check=True):
        return subprocess.run(['bash', str(NETNS)] + list(args), env=self.env, timeout=timeout,
                              check=check, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                              text=True)

    def in_ns(self, role, *cmd, timeout=30):
        """Runs cmd in role's namespace with ROS_IP / ROS_MASTER_URI / HOME of the run."""
        return self.netns('exec', role, *cmd, timeout=timeout, check=False)

    def popen(self, role, *cmd, **kwargs):
        return subprocess.Popen(['bash', str(NETNS), 'exec', role] + list(cmd), env=self.env,
                                start_new_session=True, **kwargs)

    def up_or_skip(self):
        if os.geteuid() != 0:
            pytest.skip('root is required for network namespaces')
        self.netns('down', check=False)
        up = self.netns('up', check=False)
        if up.returncode == 77:
            pytest.skip(up.stdout)
        assert up.returncode == 0, up.stdout

    def down(self):
        return self.netns('down', check=False)

    def wait_master(self, role, timeout_s=40.0):
        """True once the master at ROS_MASTER_URI answers from role's namespace."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if '/rosout' in self.in_ns(role, 'rosnode', 'list').stdout.split():
                return True
            time.sleep(1.0)
        return False
