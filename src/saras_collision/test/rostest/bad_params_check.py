#!/usr/bin/env python3
"""rostest node: colliding_regions refuses bad configuration with a clear message and exit 1."""
import os
import subprocess
import unittest

import rospkg
import rostest

PKG = rospkg.RosPack().get_path("saras_collision")
CONFIG = os.path.join(PKG, "config", "colliding_regions.yaml")


def run(name, *private):
    """Start the node with the default YAML plus @p private overrides; return (code, output)."""
    cmd = ["rosrun", "saras_collision", "colliding_regions", "__name:=" + name] + list(private)
    subprocess.run(["rosparam", "load", CONFIG, "/" + name], check=True)
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=30)
    return proc.returncode, proc.stdout.decode()


class BadParams(unittest.TestCase):
    def check(self, name, expected, *private):
        code, out = run(name, *private)
        self.assertEqual(code, 1, out)
        self.assertIn(expected, out)

    def test_negative_rate(self):
        self.check("bad_rate", "parameter /bad_rate/rate = -1 [Hz] is invalid", "_rate:=-1.0", "_vertices_file:=" + PKG + "/config/pelvis_vertices.txt")

    def test_missing_vertices_file_param(self):
        self.check("no_file", "parameter /no_file/vertices_file")

    def test_thresholds_order(self):
        self.check("bad_thresholds", "parameter /bad_thresholds/thresholds/warning", "_thresholds/warning:=0.001",
                   "_vertices_file:=" + PKG + "/config/pelvis_vertices.txt")

    def test_malformed_file_names_the_line(self):
        path = os.path.join(PKG, "test", "data", "malformed.txt")
        self.check("malformed", path + ": line 4: expected 3 coordinates", "_vertices_file:=" + path)

    def test_missing_file(self):
        self.check("missing", "/nonexistent.txt: cannot open file", "_vertices_file:=/nonexistent.txt")


if __name__ == "__main__":
    rostest.rosrun("saras_collision", "bad_params_check", BadParams)
