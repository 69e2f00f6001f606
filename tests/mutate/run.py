#!/usr/bin/env python3
"""Mutation testing for mvod: `make mutate` (docs/tests.md, "Mutation testing").

Each mutation in mutations.txt is one small edit of one source file that a correct test suite
must notice. The harness copies the tracked files of this worktree (with their uncommitted
edits) into a scratch tree, builds it once, runs the tests every mutation names on the clean
source (they must pass, or a "caught" would mean nothing), then for each mutation: restores
the clean source, applies the one edit, rebuilds only the targets those tests need (so only the
mutated file recompiles, then links), and runs those tests. A mutation is

  caught      some named test failed (or timed out);
  NOT CAUGHT  every named test passed: a hole in the suite;
  broken      its text does not occur exactly once in the file, the file is not found, or the
              mutated tree does not build: the mutation itself needs fixing.

Exit status 0 only when every mutation is caught. Standard library only.

Usage: tests/mutate/run.py [--list] [--no-baseline] [SUBSTRING...]
  SUBSTRING  run only the mutations whose id or title contains one of them
Environment: MVOD_MUTATE_DIR (scratch folder, default $TMPDIR/mvod-mutate), kept between runs
so that the next run rebuilds only what changed.
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))
LIST = os.path.join(HERE, "mutations.txt")
SCRATCH = os.environ.get("MVOD_MUTATE_DIR", os.path.join(tempfile.gettempdir(), "mvod-mutate"))
# The copy sits at SCRATCH/mvod with its build in SCRATCH/mvod/build: the same relative layout
# as a worktree and its build/, so that ccache (base_dir = SCRATCH) serves the first build from
# a worktree's objects. SCRATCH/shared points at the real data, which the data suite finds as
# ../shared/data from the source root.
SRC = os.path.join(SCRATCH, "mvod")
BUILD = os.path.join(SRC, "build")
# A mutation that makes a test hang still ends: half of each suite's timeout (unit 60 s,
# integration 600 s, data 900 s) is several times what any of them takes unmutated.
TIMEOUT_MULTIPLIER = "0.5"


def unescape(text):
    """\\n, \\t and \\\\ in a mutation's find or replace text."""
    out, i = [], 0
    while i < len(text):
        if text[i] == "\\" and i + 1 < len(text):
            out.append({"n": "\n", "t": "\t", "\\": "\\"}.get(text[i + 1], "\\" + text[i + 1]))
            i += 2
        else:
            out.append(text[i])
            i += 1
    return "".join(out)


def parse(path):
    """Mutations: blocks of `key: value` lines, each opened by `id: NAME`; # comments.

    find and replace may repeat (pairs, applied in order, all in the one file)."""
    muts, cur = [], None
    with open(path) as f:
        for no, line in enumerate(f, 1):
            line = line.rstrip("\n")
            if not line.strip() or line.lstrip().startswith("#"):
                continue
            key, sep, value = line.partition(":")
            if not sep:
                sys.exit(f"{path}:{no}: expected 'key: value', got {line!r}")
            key, value = key.strip(), value.strip()
            if key == "id":
                cur = {"id": value, "line": no}
                muts.append(cur)
            elif cur is None or key not in ("title", "module", "file", "find", "replace", "tests",
                                            "filter"):
                sys.exit(f"{path}:{no}: unknown key {key!r} (id, title, module, file, find, "
                         "replace, tests, filter)")
            elif key in ("find", "replace"):
                cur.setdefault(key, []).append(unescape(value))
            elif key == "tests":
                cur[key] = value.split()
            else:
                cur[key] = value
    for m in muts:
        for key in ("title", "module", "file", "find", "replace", "tests"):
            if key not in m:
                sys.exit(f"{path}:{m['line']}: mutation {m['id']} has no {key}")
        if len(m["find"]) != len(m["replace"]):
            sys.exit(f"{path}:{m['line']}: mutation {m['id']}: each find needs one replace")
    return muts


def tracked_files():
    out = subprocess.run(["git", "-C", REPO, "ls-files", "-z"], check=True,
                         capture_output=True).stdout.decode()
    return [p for p in out.split("\0") if p and os.path.lexists(os.path.join(REPO, p))]


def locate(files, name):
    """The one tracked file called name, wherever a move put it; None unless exactly one.

    name is a basename, or the tail of a path (calib/calibrate.c) where two files share one."""
    hits = [p for p in files if p == name or p.endswith("/" + name)]
    return hits[0] if len(hits) == 1 else None


def sync(files):
    """Makes SRC hold exactly the tracked files, rewriting only those whose bytes differ."""
    os.makedirs(SRC, exist_ok=True)
    want = set(files)
    for p in files:
        src, dst = os.path.join(REPO, p), os.path.join(SRC, p)
        with open(src, "rb") as f:
            data = f.read()
        try:
            with open(dst, "rb") as f:
                if f.read() == data:
                    continue
        except OSError:
            os.makedirs(os.path.dirname(dst), exist_ok=True)
        with open(dst, "wb") as f:
            f.write(data)
        shutil.copymode(src, dst)
    for root, dirs, names in os.walk(SRC):
        if os.path.abspath(root) == os.path.abspath(BUILD):
            dirs[:] = []
            continue
        dirs[:] = [d for d in dirs if os.path.join(root, d) != BUILD]
        for n in names:
            rel = os.path.relpath(os.path.join(root, n), SRC)
            if rel not in want:
                os.unlink(os.path.join(root, n))
    shared = os.path.join(REPO, "..", "shared")
    link = os.path.join(SCRATCH, "shared")
    if os.path.isdir(shared) and not os.path.lexists(link):
        os.symlink(os.path.abspath(shared), link)


def env():
    e = dict(os.environ)
    e["CCACHE_BASEDIR"] = SCRATCH
    return e


def run(cmd, log, extra_env=None):
    """Runs cmd with its output appended to log; its exit status."""
    e = env()
    e.update(extra_env or {})
    with open(log, "a") as f:
        f.write("$ " + " ".join(f"{k}={v}" for k, v in (extra_env or {}).items()) +
                " ".join(cmd) + "\n")
        f.flush()
        return subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT, env=e).returncode


def setup(log):
    if not os.path.exists(os.path.join(BUILD, "build.ninja")):
        if run(["meson", "setup", BUILD, SRC], log):
            sys.exit(f"mutate: meson setup failed; see {log}")


def targets_for(tests):
    """Build outputs (relative to BUILD) that the named tests run and depend on."""
    info = json.loads(subprocess.run(["meson", "introspect", "--tests", BUILD], check=True,
                                     capture_output=True).stdout)
    tinfo = json.loads(subprocess.run(["meson", "introspect", "--targets", BUILD], check=True,
                                      capture_output=True).stdout)
    by_id = {t["id"]: t for t in tinfo}
    names = {t["name"] for t in info}
    missing = [n for n in tests if n not in names]
    if missing:
        return None, missing
    out = set()
    build = os.path.abspath(BUILD) + os.sep
    for t in info:
        if t["name"] in tests:
            # A script test's program (tests/scripts/*.sh, python3) is no build output.
            if os.path.abspath(t["cmd"][0]).startswith(build):
                out.add(os.path.relpath(t["cmd"][0], BUILD))
            for d in t.get("depends", []):
                for fn in by_id.get(d, {}).get("filename", []):
                    out.add(os.path.relpath(fn, BUILD))
    return sorted(out), []


def build(targets, log):
    return run(["ninja", "-C", BUILD] + targets, log) == 0


def filters(m):
    """{test: cmocka pattern or None} for mutation m. Its filter is one pattern for every test
    it names, or TEST=PATTERN words, each for that test alone (the others run whole): a unit
    test's case and a data test's case seldom share a pattern."""
    value = m.get("filter")
    if not value:
        return {t: None for t in m["tests"]}
    words = value.split()
    if not any("=" in w for w in words):
        return {t: value for t in m["tests"]}
    per = dict(w.split("=", 1) for w in words)
    return {t: per.get(t) for t in m["tests"]}


def test(by_test, log):
    """True when every test passes (a skip counts as a pass, as in make test). by_test maps
    each test to a cmocka pattern or None: only the matching cases of that test run
    (MVOD_TEST_FILTER, read by tests/common/harness.c); one meson run per pattern."""
    for filt in sorted(set(by_test.values()), key=lambda f: f or ""):
        tests = sorted(t for t, f in by_test.items() if f == filt)
        extra = {"MVOD_TEST_FILTER": filt} if filt else {}
        if run(["meson", "test", "-C", BUILD, "--no-rebuild", "--print-errorlogs",
                "--timeout-multiplier", TIMEOUT_MULTIPLIER] + tests, log, extra) != 0:
            return False
    return True


def mutate(m, files, log):
    """(result, note) for one mutation, on a tree that is clean before and after."""
    rel = locate(files, m["file"])
    if rel is None:
        return "broken", f"no single tracked file named {m['file']}"
    path = os.path.join(SRC, rel)
    with open(path) as f:
        clean = f.read()
    mutated = clean
    for find, replace in zip(m["find"], m["replace"]):
        n = mutated.count(find)
        if n != 1:
            return "broken", f"{rel}: {find.splitlines()[0]!r} occurs {n} times, not once"
        mutated = mutated.replace(find, replace)
    targets, missing = targets_for(m["tests"])
    if missing:
        return "broken", "no test named " + ", ".join(missing)
    with open(log, "a") as f:
        f.write(f"\n==== {m['id']}: {m['title']} ({rel})\n")
    try:
        with open(path, "w") as f:
            f.write(mutated)
        if not build(targets, log):
            return "broken", "the mutated tree does not build"
        return ("NOT CAUGHT", "") if test(filters(m), log) else ("caught", "")
    finally:
        with open(path, "w") as f:
            f.write(clean)


def main(argv):
    if "-h" in argv or "--help" in argv:
        print(__doc__)
        return 0
    unknown = [a for a in argv if a.startswith("-") and a not in ("--list", "--no-baseline")]
    if unknown:
        sys.exit(f"mutate: unknown option {unknown[0]} (--list, --no-baseline, --help)")
    args = [a for a in argv if not a.startswith("-")]
    muts = parse(LIST)
    if "--list" in argv:
        for m in muts:
            print(f"{m['id']:28} {m['module']:9} {m['file']:18} {' '.join(m['tests'])}")
        return 0
    if args:
        muts = [m for m in muts if any(a in m["id"] or a in m["title"] for a in args)]
    if not muts:
        sys.exit("mutate: no mutation matches " + " ".join(args))
    os.makedirs(SCRATCH, exist_ok=True)
    log = os.path.join(SCRATCH, "mutate.log")
    open(log, "w").close()
    print(f"mutate: {len(muts)} mutations; scratch tree {SRC}; log {log}", flush=True)
    files = tracked_files()
    sync(files)
    setup(log)
    start = time.time()
    if not build([], log):
        sys.exit(f"mutate: the clean tree does not build; see {log}")
    if "--no-baseline" not in argv:
        # The clean tree against each test with each filter some mutation runs it with.
        pairs = {(t, f) for m in muts for t, f in filters(m).items()}
        for filt in sorted({f for _, f in pairs}, key=lambda f: f or ""):
            tests = sorted({t for t, f in pairs if f == filt})
            print("mutate: the clean tree against " + " ".join(tests) +
                  (f" (cases {filt})" if filt else ""), flush=True)
            if not test({t: filt for t in tests}, log):
                sys.exit(f"mutate: tests fail on the clean tree, so no result would mean "
                         f"anything; see {log}")
    rows = []
    for m in muts:
        t0 = time.time()
        result, note = mutate(m, files, log)
        rows.append((m, result, note, time.time() - t0))
        print(f"  {result:10} {m['id']:28} {time.time() - t0:6.0f} s  {note}", flush=True)
    print(f"\n| mutation | module | file | tests | result |\n|---|---|---|---|---|")
    for m, result, note, _ in rows:
        shown = f"**{result}**" if result != "caught" else result
        print(f"| {m['title']} | {m['module']} | {m['file']} | {' '.join(m['tests'])} | "
              f"{shown}{' (' + note + ')' if note else ''} |")
    counts = {r: sum(1 for _, res, _, _ in rows if res == r)
              for r in ("caught", "NOT CAUGHT", "broken")}
    print(f"\nmutate: {counts['caught']} caught, {counts['NOT CAUGHT']} not caught, "
          f"{counts['broken']} broken, of {len(rows)}, in {time.time() - start:.0f} s "
          f"(log {log})")
    return 0 if counts["caught"] == len(rows) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
