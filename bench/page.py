#!/usr/bin/env python3
"""BENCHMARKS.md's generated tables: each sits between <!-- bench:NAME --> and
<!-- /bench:NAME --> lines, and bench/run.sh measures it again.

usage: page.py names PAGE
       page.py check|update PAGE NAME HOW < MEASURED

names: the NAMEs of PAGE's blocks, one a line, in page order.
check: compares MEASURED (stdin) with block NAME; prints a diff and exits 1 when they
disagree. update: the same, but a disagreeing block is replaced by MEASURED in PAGE (an
agreeing one is left as it is, so numbers within the tolerance do not churn).
HOW says what agreeing means:
  exact    the same text
  tol=P    the same text, but instruction counts (cells written as 49.7e6) may differ by P %
           of the page's
  order    table rows only, numeric cells within a factor of 10 of the page's, other cells
           the same, a number against "-" (a column not measured here) not compared
           (wall-clock figures)
"""
import difflib
import re
import sys

NUM = re.compile(r'\s*([-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?)\s*[%x]?\s*')


def blocks(text):
    """{name: (start, end)}: line indices of the block's content, between its markers."""
    lines, found, open_ = text.split('\n'), {}, {}
    for i, line in enumerate(lines):
        m = re.fullmatch(r'<!-- (/?)bench:([\w-]+) -->', line.strip())
        if not m:
            continue
        if m.group(1):
            if m.group(2) not in open_:
                sys.exit(f'page.py: line {i + 1}: {line.strip()} closes no block')
            found[m.group(2)] = (open_.pop(m.group(2)) + 1, i)
        else:
            open_[m.group(2)] = i
    if open_:
        sys.exit(f'page.py: block {sorted(open_)[0]} is not closed')
    return lines, found


def number(cell):
    m = NUM.fullmatch(cell)
    return float(m.group(1)) if m else None


def cells_agree(page, measured, how):
    a, b = number(page), number(measured)
    if how == 'order':
        if a is None and b is None:
            return page.strip() == measured.strip()
        return a is None or b is None or (a == b == 0) or (a > 0 and b > 0 and 0.1 <= b / a <= 10)
    if a is None or b is None or how == 'exact':
        return page.strip() == measured.strip()
    if 'e' not in page.lower():
        return page.strip() == measured.strip()
    tol = float(how.split('=')[1]) / 100
    return abs(a - b) <= tol * abs(a)


def agree(page, measured, how):
    if how == 'exact':
        return page == measured
    if how == 'order':
        page = [l for l in page if l.startswith('|')]
        measured = [l for l in measured if l.startswith('|')]
    if len(page) != len(measured):
        return False
    for p, m in zip(page, measured):
        pc, mc = p.split('|'), m.split('|')
        if len(pc) != len(mc) or not all(cells_agree(x, y, how) for x, y in zip(pc, mc)):
            return False
    return True


def main():
    if len(sys.argv) == 3 and sys.argv[1] == 'names':
        _, found = blocks(open(sys.argv[2]).read())
        print('\n'.join(sorted(found, key=lambda n: found[n][0])))
        return 0
    if len(sys.argv) != 5 or sys.argv[1] not in ('check', 'update'):
        sys.exit(__doc__)
    what, path, name, how = sys.argv[1:]
    text = open(path).read()
    lines, found = blocks(text)
    if name not in found:
        sys.exit(f'page.py: {path} has no block {name}')
    start, end = found[name]
    page = lines[start:end]
    measured = sys.stdin.read().rstrip('\n').split('\n')
    if agree(page, measured, how):
        return 0
    # Within a tolerance, the diff shows only the lines that disagree.
    shown = measured
    if how != 'exact' and len(page) == len(measured):
        shown = [p if agree([p], [m], how) else m for p, m in zip(page, measured)]
    sys.stdout.writelines(difflib.unified_diff(
        [l + '\n' for l in page], [l + '\n' for l in shown],
        f'{path} ({name})', f'measured ({name}, {how})'))
    if what == 'update':
        lines[start:end] = measured
        with open(path, 'w') as f:
            f.write('\n'.join(lines))
        print(f'page.py: {name} rewritten in {path}')
        return 0
    return 1


if __name__ == '__main__':
    sys.exit(main())
