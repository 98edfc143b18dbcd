#!/usr/bin/env python3
"""Sum JUnit XML files (gtest, rostest, pytest).

  junit_counts.py FILE...             print "passed failed skipped"
  junit_counts.py --failures FILE...  print one line per failed test case: file, case, first message line
"""
import os
import sys
import xml.etree.ElementTree as ET


def cases(path):
    """(name, outcome, message) per test case; outcome is pass, fail or skip."""
    try:
        root = ET.parse(path).getroot()
    except (ET.ParseError, OSError) as e:
        return [('<result file>', 'fail', 'unreadable: %s' % e)]  # never a silent pass
    suites = [root] if root.tag == 'testsuite' else root.iter('testsuite')
    out = []
    for suite in suites:
        for case in suite.iter('testcase'):
            bad = case.find('failure')
            if bad is None:
                bad = case.find('error')
            name = '%s.%s' % (case.get('classname', ''), case.get('name', ''))
            if bad is not None:
                text = (bad.get('message') or bad.text or '').strip().splitlines()
                out.append((name, 'fail', text[0][:160] if text else ''))
            elif case.find('skipped') is not None:
                out.append((name, 'skip', ''))
            else:
                out.append((name, 'pass', ''))
    return out


def counts(path):
    outcomes = [c[1] for c in cases(path)]
    return outcomes.count('pass'), outcomes.count('fail'), outcomes.count('skip')


def main(argv):
    if argv and argv[0] == '--failures':
        for path in argv[1:]:
            for name, outcome, msg in cases(path):
                if outcome == 'fail':
                    print('FAILED %s: %s: %s' % (os.path.basename(path), name, msg))
        return
    tot = [0, 0, 0]
    for path in argv:
        for i, v in enumerate(counts(path)):
            tot[i] += v
    print(*tot)


if __name__ == '__main__':
    main(sys.argv[1:])
