#!/usr/bin/env python3
"""Print "passed failed skipped" summed over JUnit XML files (gtest, rostest, pytest)."""
import sys
import xml.etree.ElementTree as ET


def counts(path):
    try:
        root = ET.parse(path).getroot()
    except (ET.ParseError, OSError):
        return 0, 1, 0  # an unreadable result file is a failure, never a silent pass
    suites = [root] if root.tag == 'testsuite' else root.iter('testsuite')
    p = f = s = 0
    for suite in suites:
        for case in suite.iter('testcase'):
            if case.find('failure') is not None or case.find('error') is not None:
                f += 1
            elif case.find('skipped') is not None:
                s += 1
            else:
                p += 1
    return p, f, s


if __name__ == '__main__':
    tot = [0, 0, 0]
    for arg in sys.argv[1:]:
        for i, v in enumerate(counts(arg)):
            tot[i] += v
    print(*tot)
