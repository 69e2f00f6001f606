#!/usr/bin/env python3
"""Every shell example of README.md and docs/*.md runs, or says why it cannot (issue 38).

Usage: tests/docs/examples.py [--keep] [PAGE.md ...]
  PAGE.md   only these pages (paths from the source tree; default README.md and docs/*.md)
  --keep    keep the scratch folder and print where it is
Environment (meson test sets it): MVOD_SRCDIR (the source tree), MVOD_BUILDDIR (its build),
MVOD_DATA (../shared/data). Exit status: 0 when every example passed (examples that need
../shared/data are skipped, and listed, when it is absent), 1 when one failed or a page breaks a
rule below, 2 on a usage error.

How a page writes its examples (the test refuses a page that breaks one of these rules):

Fences. Every fenced block names its language. Shell examples are ```sh (commands; what they
print is not checked, comments are free) or ```console (a transcript: a line starting `$ ` is a
command, one ending in `\\` continues on the next line, and the lines up to the next `$ ` are
what the command prints). ```bash, ```shell and ```zsh are refused, so that no shell example
escapes this test. Blocks of any other language (ini, json, c, python, text) are not run, but a
```text block with a line starting `$ ` or `mvod ` is refused: it is a shell example.

Not run. A shell block that cannot run here has on the line right before its fence
`<!-- not run: CATEGORY: REASON -->`, CATEGORY one of CATEGORIES below and a REASON of its own.
Every other shell block runs.

Where blocks run. Each page gets a scratch folder laid out as a clone after `make demo`: the
source tree's top-level entries (linked, not copied), `build` (the build being tested),
`demo-out/` (made by the Makefile's own demo recipe, `make -n demo` past its build step), and
`../shared/data` beside it (linked, when it exists). PATH starts with build/, build/tools/ and
build/examples/, HOME is a scratch folder, LCM_DEFAULT_URL is memq://. A page's blocks run in
order in its folder, so a later block may use what an earlier one wrote, as a reader would.
An ```sh block runs as one `bash -e -o pipefail` script and must exit 0. In a ```console block
each command runs on its own (`bash -o pipefail -c`) in a pseudo-terminal, so that stdout and
stderr interleave as a reader sees them, and must exit 0: a block that shows a failure shows
the status too (`mvod ... ; echo "exit status $?"`). A console line `$ make demo` runs the
Makefile's demo recipe (make -n demo) past its build step: the test builds and installs nothing.
A block that names ../shared/data is skipped, and listed, when that folder is absent.

LCM. No runnable block may publish or listen beyond its own process: a block is refused when
it names a URL (SCHEME://) other than memq:// or file://, when it runs `mvod` (run, or no command) or `mvod view` without an
explicit `--lcm-url memq://...` or `--lcm-url file://...` (`--help`, `--print-config`,
`--version` and `--list-cameras` publish nothing), when any `--lcm-url` is another URL, or
when it runs lcm-logger, lcm-logplayer or lcm-spy. Nor may it name /tmp: a block writes into
its page's folder, by relative paths, so that two runs of this test never meet.

Shown output. The lines a console block shows must be the lines the command prints, in order,
each whole (trailing blanks aside), with three wildcards:
  - a shown line `...` stands for any number of lines, none included;
  - `...` inside a line stands for any text within that line;
  - a number that measures time varies from run to run and machine to machine, and matches any
    number: one followed by ` s`, ` ms` or ` fps` (`0.30 s (168.4 fps)`, `median 8.8 ms`), or
    the value of a field named `fps=` or ending in `_ms=`, `_s=` or `_kb=`.
Every other number is exact: accuracy, counts, calibrations. A count that follows the wall
clock (the status messages mvod sends once a second) is shown as `...`. mvod-synth renders the same bytes
from the same arguments, and mvod's results on a file do not depend on the machine's speed, so
a changed default, a changed message or a changed result makes the page fail here.

Links. A relative link in a page (`[x](docs/y.md#z)`) must name a file of the tree, and its
anchor a heading of that page (GitHub's slugs).

The README's test command. .ci/run runs `make test`, the README's test command: the README must
show that command, on its own line of an ```sh block.
"""
import os
import pty
import re
import select
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import time

CATEGORIES = {
    'camera': 'needs a camera (v4l2:, libcamera:) or lists the attached ones',
    'system': 'changes the system: apt, make install, users, systemd, sudo',
    'display': 'opens a window',
    'network': 'sends or listens on the network (LCM multicast, pip)',
    'dataset': 'needs a public dataset that ../shared/data does not hold',
    'long': 'builds, or runs for minutes (make test, make mutate, make bench, a full sweep)',
    'yours': "stands for the reader's own files (a recording of their board, their camera)",
}
SHELL_LANGS = ('sh', 'console')
REFUSED_LANGS = ('bash', 'shell', 'zsh')
MARKER = re.compile(r'^<!-- not run: ([a-z]+): (\S.*?) -->$')
FENCE = re.compile(r'^(\s*)(```+)\s*([^\s`]*)\s*$')
BLOCK_TIMEOUT = 300
QUIET_FLAGS = ('--help', '-h', '--help-all', '--print-config', '--version', '--list-cameras')
LCM_TOOLS = ('lcm-logger', 'lcm-logplayer', 'lcm-spy')
MVOD_COMMANDS = ('run', 'calibrate', 'mount', 'board', 'calib-convert', 'bench', 'view',
                 'speed-log')
NUMBER = r'\d+(?:\.\d+)?'
TIMING = re.compile(NUMBER + r'(?= ?(?:ms|s|fps)\b)|(?<=fps=)' + NUMBER +
                    r'|(?<=_ms=)' + NUMBER + r'|(?<=_s=)' + NUMBER + r'|(?<=_kb=)' + NUMBER)


class Block:
    def __init__(self, page, line, lang, text, marker):
        self.page, self.line, self.lang, self.text, self.marker = page, line, lang, text, marker

    def where(self):
        return '%s:%d' % (self.page, self.line)


def parse(page, text):
    """The fenced blocks of a page, and the problems of its fences and markers."""
    blocks, problems = [], []
    lines = text.split('\n')
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        indent, ticks, lang = m.group(1), m.group(2), m.group(3)
        start = i
        body = []
        i += 1
        while i < len(lines) and not re.match(r'^\s*' + ticks + r'\s*$', lines[i]):
            body.append(lines[i][len(indent):] if lines[i].startswith(indent) else lines[i].lstrip())
            i += 1
        if i == len(lines):
            problems.append('%s:%d: a fence that never closes' % (page, start + 1))
        i += 1
        prev = lines[start - 1].strip() if start > 0 else ''
        marker = MARKER.match(prev)
        where = '%s:%d' % (page, start + 1)
        if prev.startswith('<!-- not run') and not marker:
            problems.append('%s: write the marker as <!-- not run: CATEGORY: reason -->' % where)
        if marker and marker.group(1) not in CATEGORIES:
            problems.append('%s: unknown category %r (one of %s)' %
                            (where, marker.group(1), ', '.join(CATEGORIES)))
        if not lang:
            problems.append('%s: a fence without a language (sh, console, ini, json, text, ...)'
                            % where)
        elif lang in REFUSED_LANGS:
            problems.append('%s: ```%s: write shell examples as ```sh or ```console' % (where, lang))
        elif lang not in SHELL_LANGS:
            if marker:
                problems.append('%s: a not-run marker on a ```%s block, which never runs'
                                % (where, lang))
            if lang == 'text' and any(l.startswith(('$ ', 'mvod ')) for l in body):
                problems.append('%s: a shell example in a ```text block: make it sh or console'
                                % where)
            continue
        blocks.append(Block(page, start + 1, lang, '\n'.join(body), marker))
    return blocks, problems


def console_commands(text):
    """A console block as [(command, [shown output lines])]."""
    out = []
    lines = text.split('\n')
    i = 0
    while i < len(lines):
        line = lines[i]
        if not line.startswith('$ '):
            if out:
                out[-1][1].append(line.rstrip())
            elif line.strip():
                return None
            i += 1
            continue
        cmd = line[2:]
        while cmd.endswith('\\') and i + 1 < len(lines):
            i += 1
            cmd += '\n' + lines[i]
        out.append((cmd, []))
        i += 1
    for _, shown in out:
        while shown and not shown[-1]:
            shown.pop()
    return out


def block_script(block):
    """The shell text of a block: a console block's commands, an sh block whole."""
    if block.lang == 'console':
        cmds = console_commands(block.text) or []
        return '\n'.join(c for c, _ in cmds)
    return block.text


def simple_commands(script):
    """The simple commands of a shell text, each a list of words (near enough for the rules)."""
    script = re.sub(r'\\\n', ' ', script)
    cmds = []
    for line in script.split('\n'):
        lex = shlex.shlex(line, posix=True, punctuation_chars=';&|()<>')
        lex.whitespace_split = True
        lex.commenters = '#'
        try:
            words = list(lex)
        except ValueError:
            words = line.split()
        cmd = []
        for w in words + [';']:
            if w and all(c in ';&|()<>' for c in w):
                if cmd:
                    cmds.append(cmd)
                cmd = []
            else:
                cmd.append(w)
    return cmds


def lcm_problems(block):
    """Why a runnable block could publish or listen beyond its process, if it could."""
    script = block_script(block)
    problems = []
    for scheme in sorted(set(re.findall(r'\b([a-z][a-z0-9+.-]*)://', script)) - {'memq', 'file'}):
        problems.append('names a %s:// URL: only memq:// or file:// here' % scheme)
    if re.search(r'(^|[\s\'"=:(])/tmp/', script):
        problems.append('names /tmp: write into the page\'s folder by a relative path')
    for words in simple_commands(script):
        while words and (re.match(r'^[A-Za-z_][A-Za-z0-9_]*=', words[0]) or
                         words[0] in ('env', 'time', 'nice', 'exec', 'timeout')):
            words = words[1:]
        if not words:
            continue
        prog = os.path.basename(words[0])
        urls = [w.split('=', 1)[1] for w in words if w.startswith('--lcm-url=')]
        urls += [words[k + 1] for k, w in enumerate(words[:-1]) if w == '--lcm-url']
        for url in urls:
            if not url.startswith(('memq://', 'file://')):
                problems.append('%s: --lcm-url %s: only memq:// or file:// here' % (prog, url))
        if prog in LCM_TOOLS:
            problems.append('runs %s, which talks to the LCM network' % prog)
        if prog != 'mvod':
            continue
        sub = words[1] if len(words) > 1 and words[1] in MVOD_COMMANDS else 'run'
        if sub in ('run', 'view') and not urls and not any(w in QUIET_FLAGS for w in words):
            problems.append('runs mvod %s without --lcm-url memq:// or file://: it would publish '
                            'to LCM multicast' % sub)
    return problems


def line_regex(shown):
    """A shown output line as a regular expression of the real line (see the module's doc)."""
    parts = []
    for k, piece in enumerate(shown.split('...')):
        if k:
            parts.append('.*?')
        pos = 0
        for m in TIMING.finditer(piece):
            parts.append(re.escape(piece[pos:m.start()]))
            parts.append(NUMBER)
            pos = m.end()
        parts.append(re.escape(piece[pos:]))
    return re.compile(''.join(parts))


def output_matches(shown, real):
    """Whether the real lines are the shown ones, under the wildcards."""
    regexes = [None if s.strip() == '...' else line_regex(s.rstrip()) for s in shown]
    memo = {}

    def match(i, j):
        if (i, j) in memo:
            return memo[(i, j)]
        if i == len(regexes):
            ok = j == len(real)
        elif regexes[i] is None:
            ok = any(match(i + 1, k) for k in range(j, len(real) + 1))
        else:
            ok = j < len(real) and regexes[i].fullmatch(real[j]) is not None and match(i + 1, j + 1)
        memo[(i, j)] = ok
        return ok
    return match(0, 0)


def run_in_pty(cmd, cwd, env, timeout=BLOCK_TIMEOUT):
    """A command in a pseudo-terminal: (exit status, output lines); None status on timeout."""
    master, slave = pty.openpty()
    proc = subprocess.Popen(['bash', '-o', 'pipefail', '-c', cmd], cwd=cwd, env=env,
                            stdin=subprocess.DEVNULL, stdout=slave, stderr=slave,
                            start_new_session=True)
    os.close(slave)
    data = b''
    deadline = time.monotonic() + timeout
    timed_out = False
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            timed_out = True
            break
        ready, _, _ = select.select([master], [], [], left)
        if not ready:
            continue
        try:
            chunk = os.read(master, 65536)
        except OSError:  # EIO: every holder of the terminal's other end has closed it
            break
        if not chunk:
            break
        data += chunk
    if timed_out:
        os.killpg(proc.pid, signal.SIGKILL)
    status = proc.wait()
    os.close(master)
    text = data.decode('utf-8', 'replace').replace('\r\n', '\n').replace('\r', '\n')
    lines = [l.rstrip() for l in text.split('\n')]
    while lines and not lines[-1]:
        lines.pop()
    return (None if timed_out else status), lines


def demo_recipe(src, cwd):
    """The Makefile's demo recipe past its build step, as make -n prints it from cwd."""
    out = subprocess.run(['make', '-n', '-s', '-f', os.path.join(src, 'Makefile'), 'demo',
                          'BUILDDIR=build', 'DEMODIR=demo-out'], cwd=cwd, capture_output=True,
                         text=True)
    lines = out.stdout.split('\n')
    starts = [k for k, l in enumerate(lines) if l.startswith('meson compile -C build')]
    if out.returncode != 0 or not starts:
        sys.exit('examples: make -n demo printed no build step to start after:\n' + out.stdout +
                 out.stderr)
    return '\n'.join(lines[starts[-1] + 1:])


def copy_or_link(src, dst):
    """The demo's video is linked (46 MB, only ever read, and mvod replaces a file it writes
    by renaming a new one over it), every other file copied."""
    if src.endswith('.mkv'):
        os.link(src, dst)
    else:
        shutil.copy2(src, dst)


class Pages:
    def __init__(self, src, build, data, scratch):
        self.src, self.build, self.data, self.scratch = src, build, data, scratch
        self.failures, self.skipped, self.ran, self.not_run = [], [], 0, {}
        self.env = dict(os.environ)
        self.env['PATH'] = ':'.join([build, os.path.join(build, 'tools'),
                                     os.path.join(build, 'examples'), os.environ['PATH']])
        self.env['LCM_DEFAULT_URL'] = 'memq://'
        self.env['HOME'] = os.path.join(scratch, 'home')
        self.env['TMPDIR'] = os.path.join(scratch, 'tmp')
        self.env.pop('DISPLAY', None)
        self.env.pop('WAYLAND_DISPLAY', None)
        os.makedirs(self.env['HOME'])
        os.makedirs(self.env['TMPDIR'])
        self.demo = None

    def clone(self, name):
        """A folder laid out as a clone beside ../shared/data, after make demo."""
        root = os.path.join(self.scratch, 'pages', name)
        cwd = os.path.join(root, 'mvod')
        os.makedirs(cwd)
        for entry in os.listdir(self.src):
            if entry in ('.git', 'demo-out') or entry.startswith('build'):
                continue
            os.symlink(os.path.join(self.src, entry), os.path.join(cwd, entry))
        os.symlink(self.build, os.path.join(cwd, 'build'))
        if os.path.isdir(self.data):
            os.makedirs(os.path.join(root, 'shared'))
            os.symlink(self.data, os.path.join(root, 'shared', 'data'))
        if self.demo is None:
            self.demo = os.path.join(self.scratch, 'demo')
            os.makedirs(self.demo)
            os.symlink(self.build, os.path.join(self.demo, 'build'))
            r = subprocess.run(['bash', '-e', '-c', demo_recipe(self.src, self.demo)],
                               cwd=self.demo, env=self.env, capture_output=True, text=True)
            if r.returncode != 0:
                sys.exit('examples: the demo recipe failed:\n' + r.stdout + r.stderr)
        shutil.copytree(os.path.join(self.demo, 'demo-out'), os.path.join(cwd, 'demo-out'),
                        copy_function=copy_or_link)
        return cwd

    def fail(self, block, what):
        self.failures.append('%s: %s' % (block.where(), what))
        print('FAIL %s: %s' % (block.where(), what), flush=True)

    def run_page(self, page, blocks):
        cwd = None
        for block in blocks:
            if block.marker:
                cat = block.marker.group(1)
                self.not_run[cat] = self.not_run.get(cat, 0) + 1
                continue
            problems = lcm_problems(block)
            if problems:
                self.fail(block, 'refused: ' + '; '.join(problems))
                continue
            if '../shared/data' in block.text and not os.path.isdir(self.data):
                self.skipped.append(block.where())
                continue
            if cwd is None:
                cwd = self.clone(page.replace('/', '_'))
            started = time.monotonic()
            self.run_block(block, cwd)
            self.ran += 1
            print('ran  %s (%s, %.1f s)' % (block.where(), block.lang, time.monotonic() - started),
                  flush=True)

    def run_block(self, block, cwd):
        if block.lang == 'sh':
            r = subprocess.run(['bash', '-e', '-o', 'pipefail', '-c', block.text], cwd=cwd,
                               env=self.env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True, timeout=BLOCK_TIMEOUT)
            if r.returncode != 0:
                self.fail(block, 'exit status %d:\n%s\n--- output:\n%s' %
                          (r.returncode, block.text, r.stdout))
            return
        commands = console_commands(block.text)
        if not commands:
            self.fail(block, 'a console block must start with a `$ ` command line')
            return
        for cmd, shown in commands:
            if cmd.strip() == 'make demo':
                cmd = demo_recipe(self.src, cwd)
            status, real = run_in_pty(cmd, cwd, self.env)
            if status != 0:
                self.fail(block, '$ %s\nexit status %s; it printed:\n%s' %
                          (cmd, 'timeout' if status is None else status, '\n'.join(real)))
                return
            if not output_matches(shown, real):
                self.fail(block, '$ %s\nthe page shows:\n%s\n--- it printed:\n%s' %
                          (cmd, '\n'.join(shown), '\n'.join(real)))
                return


SLUG_DROP = re.compile(r'[^\w\- ]')


def slug(heading):
    return SLUG_DROP.sub('', heading.strip().lower().replace('`', '')).replace(' ', '-')


def anchors(text):
    seen, out = {}, set()
    in_fence = False
    for line in text.split('\n'):
        if FENCE.match(line):
            in_fence = not in_fence
            continue
        m = re.match(r'^#{1,6}\s+(.*?)\s*#*\s*$', line)
        if m and not in_fence:
            s = slug(m.group(1))
            n = seen.get(s, 0)
            seen[s] = n + 1
            out.add(s if n == 0 else '%s-%d' % (s, n))
    return out


def link_problems(src, page, text):
    problems = []
    prose = re.sub(r'```.*?```', '', text, flags=re.S)
    prose = re.sub(r'`[^`\n]*`', '', prose)
    for m in re.finditer(r'\]\(([^)\s]+)\)', prose):
        target = m.group(1)
        if re.match(r'^[a-z]+:', target):
            continue
        path, _, anchor = target.partition('#')
        full = os.path.normpath(os.path.join(src, os.path.dirname(page), path)) if path else \
            os.path.join(src, page)
        if not os.path.exists(full):
            problems.append('%s: link to %s: no such file' % (page, target))
            continue
        if anchor and full.endswith('.md'):
            with open(full, encoding='utf-8') as f:
                if anchor not in anchors(f.read()):
                    problems.append('%s: link to %s: no such heading' % (page, target))
    return problems


def ci_command_problems(src, readme_blocks):
    with open(os.path.join(src, '.ci', 'run'), encoding='utf-8') as f:
        ci = [l.strip() for l in f if l.strip() and not l.startswith('#') and
              not l.startswith(('set ', 'cd '))]
    if not ci:
        return ['.ci/run: no command found']
    lines = [l.split('#')[0].strip() for b in readme_blocks if b.lang == 'sh'
             for l in b.text.split('\n')]
    if ci[-1] not in lines:
        return ['README.md: .ci/run runs `%s`, which no ```sh block of the README shows' % ci[-1]]
    return []


def main(argv):
    keep = '--keep' in argv
    args = [a for a in argv if a != '--keep']
    if any(a.startswith('-') for a in args):
        print(__doc__)
        return 2
    try:
        src = os.path.realpath(os.environ['MVOD_SRCDIR'])
        build = os.path.realpath(os.environ['MVOD_BUILDDIR'])
    except KeyError:
        print('examples: set MVOD_SRCDIR and MVOD_BUILDDIR (meson test does)', file=sys.stderr)
        return 2
    data = os.path.realpath(os.environ.get('MVOD_DATA', os.path.join(src, '..', 'shared', 'data')))
    pages = args or ['README.md'] + sorted(
        os.path.join('docs', f) for f in os.listdir(os.path.join(src, 'docs')) if f.endswith('.md'))
    problems, parsed = [], []
    for page in pages:
        with open(os.path.join(src, page), encoding='utf-8') as f:
            text = f.read()
        blocks, p = parse(page, text)
        problems += p + link_problems(src, page, text)
        if page == 'README.md':
            problems += ci_command_problems(src, blocks)
        parsed.append((page, blocks))
    for p in problems:
        print('FAIL ' + p)
    scratch = tempfile.mkdtemp(prefix='mvod-docs-')
    runner = Pages(src, build, data, scratch)
    try:
        for page, blocks in parsed:
            runner.run_page(page, blocks)
    finally:
        if keep:
            print('examples: scratch folder kept: ' + scratch)
        else:
            shutil.rmtree(scratch, ignore_errors=True)
    print('examples: %d blocks ran, %d not run (%s), %d skipped without %s' %
          (runner.ran, sum(runner.not_run.values()),
           ', '.join('%s %d' % kv for kv in sorted(runner.not_run.items())) or 'none',
           len(runner.skipped), data))
    for s in runner.skipped:
        print('skipped ' + s)
    failed = len(runner.failures) + len(problems)
    if failed:
        print('examples: %d failures' % failed)
    return 1 if failed else 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
