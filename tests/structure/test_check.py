#!/usr/bin/env python3
"""check.py can fail: each rule on a small tree that breaks it, and on one that keeps it.

Each case writes a fixture tree (src/, include/mvod/) to a temporary folder, with the symbol
table `nm -A` would print for its objects (check.py --nm-output), runs check.py and asserts its
exit status and lines. One case runs the real nm on objects compiled from a fixture. Standard
library only; a second or two.
"""
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

CHECK = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'check.py')


def body(n, depth=1):
    """n lines of a function body, indented depth tabs."""
    return ''.join('\t' * depth + f'x += {i};\n' for i in range(n))


def nm_lines(symbols):
    """`nm -A libmvod.a` for {source: (defined, undefined)}, members named as meson names them;
    a defined symbol is of type T unless given as 'TYPE name'."""
    out = []
    for source, (defined, undefined) in symbols.items():
        member = 'libmvod.a:libmvod.a.p/' + source.replace('/', '_') + '.o'
        out += [f'{member}:0000000000000000 {s if " " in s else "T " + s}' for s in defined]
        out += [f'{member}:                 U {s}' for s in undefined]
    return '\n'.join(out) + '\n'


class Fixture(unittest.TestCase):
    def setUp(self):
        self.root = tempfile.mkdtemp(prefix='structure-')
        self.addCleanup(shutil.rmtree, self.root)

    def write(self, files):
        for path, text in files.items():
            full = os.path.join(self.root, path)
            os.makedirs(os.path.dirname(full), exist_ok=True)
            with open(full, 'w', encoding='utf-8') as f:
                f.write(text)

    def run_check(self, files, symbols, *, objects=None):
        """check.py's exit status and output lines on the tree files and nm table symbols."""
        self.write(files)
        if objects is None:
            table = os.path.join(self.root, 'nm.txt')
            with open(table, 'w', encoding='utf-8') as f:
                f.write(nm_lines(symbols))
            args = ['--nm-output', table]
        else:
            args = objects
        r = subprocess.run([sys.executable, CHECK, self.root] + args, capture_output=True,
                           text=True, timeout=30)
        return r.returncode, r.stdout.splitlines()

    def assertViolations(self, result, *expected):
        """Exit status 1 and, for each of expected, one line containing it; no other line."""
        status, lines = result
        self.assertEqual(status, 1, lines)
        self.assertEqual(len(lines), len(expected), lines)
        for part in expected:
            self.assertTrue(any(part in line for line in lines), f'{part!r} not in {lines}')


# One clean tree: a public header and its implementation, a shared helper, functions of 60
# lines (multi-line signature, static inline in a header, C++ member, extern "C" block) and
# what must not be taken for functions (initialisers at column 0 longer than 60 lines, one
# with its `{` alone on a line, a lambda body, a struct).
CLEAN = {
    'include/mvod/a.h': 'int a_run(int x);\nstruct a_result { int n; };\n',
    'src/a/a.c': (
        '#include "mvod/a.h"\n#include "util/u.h"\n#include <stdio.h>\n#include "mvod_gen_t.h"\n'
        'static const int table[] = {\n' + '\t1,\n' * 70 + '};\n\n'
        'static const int other[] =\n{\n' + '\t2,\n' * 70 + '};\n\n'
        'static int sixty(int x,\n\t\t int y)\n{\n' + body(60) + '}\n\n'
        'int a_run(int x)\n{\n\treturn u_f(x) + table[0];\n}\n'),
    'src/a/b.cpp': (
        '#include "mvod/a.h"\n\nstruct shape {\n\tint n;\n};\n\n'
        'class counter {\n\tint operator()(int x) const\n\t{\n' + body(60, 2) + '\t}\n};\n\n'
        'extern "C" {\nint b_f(int x);\n}\n\n'
        'extern "C" int b_f(int x)\n{\n\treturn guarded([&] {\n' + body(58, 2) + '\t});\n}\n'),
    'src/util/u.h': 'static inline int u_g(int x)\n{\n' + body(60) + '}\nint u_f(int x);\n',
    'src/util/u.c': '#include "u.h"\nint u_f(int x)\n{\n\treturn x;\n}\n',
}
CLEAN_NM = {'src/a/a.c': (['a_run'], ['u_f']), 'src/a/b.cpp': (['b_f'], []),
            'src/util/u.c': (['u_f'], [])}


class CleanTree(Fixture):
    def test_clean_tree_passes(self):
        self.assertEqual(self.run_check(CLEAN, CLEAN_NM), (0, []))

    def test_no_object_of_src_is_an_error(self):
        self.assertEqual(self.run_check(CLEAN, {})[0], 2)


class Circles(Fixture):
    def test_include_circle(self):
        files = {'src/a/x.c': '#include "y.h"\n', 'src/a/x.h': '',
                 'src/a/y.c': '#include "x.h"\n', 'src/a/y.h': ''}
        self.assertViolations(
            self.run_check(files, {'src/a/x.c': (['f'], [])}),
            'src/a/x.c:1: module circle: src/a/x --include "y.h" (src/a/x.c:1)--> '
            'src/a/y --include "x.h" (src/a/y.c:1)--> src/a/x')

    def test_call_circle_of_modules_and_folders(self):
        files = {'src/a/p.c': 'void p_f(void) { q_f(); }\n',
                 'src/b/q.c': '\n\nvoid q_f(void) { p_f(); }\n'}
        symbols = {'src/a/p.c': (['p_f'], ['q_f']), 'src/b/q.c': (['q_f'], ['p_f'])}
        self.assertViolations(
            self.run_check(files, symbols),
            'src/a/p.c:1: module circle: src/a/p --call q_f (src/a/p.c:1)--> '
            'src/b/q --call p_f (src/b/q.c:3)--> src/a/p',
            'src/a/p.c:1: folder circle: src/a --call q_f (src/a/p.c:1)--> '
            'src/b --call p_f (src/b/q.c:3)--> src/a')

    def test_circle_through_a_public_header(self):
        # src/s uses the pipeline's type from its public header, the pipeline calls src/s.
        files = {'include/mvod/p.h': '/* s_create is not declared here */\n'
                                     'struct p_summary { int n; };\nint p_run(void);\n',
                 'src/p.c': '#include "mvod/p.h"\nint p_run(void)\n{\n\treturn s_create();\n}\n',
                 'src/s/s.c': '#include "mvod/p.h"\nint s_create(void)\n{\n\treturn 0;\n}\n'}
        symbols = {'src/p.c': (['p_run'], ['s_create']), 'src/s/s.c': (['s_create'], [])}
        self.assertViolations(
            self.run_check(files, symbols),
            'src/p.c:4: module circle: src/p --call s_create (src/p.c:4)--> src/s/s '
            '--header "mvod/p.h" declares p_run, defined in src/p (src/s/s.c:1)--> src/p',
            'src/p.c:4: folder circle: src --call s_create')

    def test_implementers_of_one_public_header_make_no_circle(self):
        files = {'include/mvod/c.h': 'int c1_f(void);\nint c2_f(void);\n',
                 'src/c/c1.c': '#include "mvod/c.h"\n', 'src/c/c2.c': '#include "mvod/c.h"\n'}
        symbols = {'src/c/c1.c': (['c1_f'], ['c2_f']), 'src/c/c2.c': (['c2_f'], [])}
        self.assertEqual(self.run_check(files, symbols), (0, []))

    def test_no_folder_circle_through_public_headers(self):
        # include/mvod holds declarations: src/util -> include/mvod -> src/util is no circle.
        files = {'include/mvod/p.h': '#include "util/x.h"\n', 'src/util/x.h': '',
                 'src/util/y.c': '#include "mvod/p.h"\n'}
        self.assertEqual(self.run_check(files, {'src/util/y.c': (['f'], [])}), (0, []))

    def test_own_public_header_through_another_makes_no_circle(self):
        # src/p/p.c implements p.h and includes q.h, which includes p.h.
        files = {'include/mvod/p.h': 'int p_run(void);\n', 'include/mvod/q.h': '#include "p.h"\n',
                 'src/p/p.c': '#include "mvod/q.h"\n'}
        self.assertEqual(self.run_check(files, {'src/p/p.c': (['p_run'], [])}), (0, []))

    def test_weak_definitions_make_no_call_edge(self):
        # Two shims carry the same template instantiation (W); neither depends on the other.
        files = {'src/a/x.cpp': '', 'src/b/y.cpp': ''}
        symbols = {'src/a/x.cpp': (['W _Z3tplIiEvv', 'x_f'], ['y_f']),
                   'src/b/y.cpp': (['y_f'], ['_Z3tplIiEvv'])}
        self.assertEqual(self.run_check(files, symbols), (0, []))

    def test_real_nm_on_compiled_objects(self):
        cc = shutil.which('cc')
        if cc is None:
            self.skipTest('no C compiler')
        files = {'src/a/p.c': 'void q_f(void);\nvoid p_f(void) { q_f(); }\n',
                 'src/b/q.c': 'void p_f(void);\nvoid q_f(void) { p_f(); }\n'}
        self.write(files)
        objects = []
        for source in files:
            obj = os.path.join(self.root, source.replace('/', '_') + '.o')
            subprocess.run([cc, '-c', os.path.join(self.root, source), '-o', obj], check=True)
            objects.append(obj)
        archive = os.path.join(self.root, 'libx.a')
        subprocess.run(['ar', 'rc', archive] + objects, check=True)
        self.assertViolations(self.run_check({}, None, objects=[archive]),
                              'module circle: src/a/p --call q_f', 'folder circle: src/a')


class Layers(Fixture):
    def test_layers(self):
        files = {
            'src/vo/vo.c': '#include "vo/map/m.h"\n',                 # down: fine
            'src/vo/map/m.h': '', 'src/vo/map/m.c': '#include "vo/core/c.h"\n',  # fine
            'src/vo/core/c.h': '',
            'src/vo/twoview/t.c': '\n#include "vo/map/m.h"\n',       # the other mode
            'src/vo/frontend/f.c': '#include "vo/geom/g.h"\n',       # another part
            'src/vo/geom/g.h': '',
            'src/vo/core/c.c': '#include "vo/optim/o.h"\n',          # up
            'src/vo/optim/o.h': '',
        }
        self.assertViolations(
            self.run_check(files, {'src/vo/vo.c': (['f'], [])}),
            'src/vo/twoview/t.c:2: layer: src/vo/twoview (modes) may not depend on src/vo/map '
            '(modes), only on lower layers (include "vo/map/m.h")',
            'src/vo/frontend/f.c:1: layer: src/vo/frontend (parts) may not depend on '
            'src/vo/geom (parts)',
            'src/vo/core/c.c:1: layer: src/vo/core (core) may not depend on src/vo/optim (parts)')


class FunctionLength(Fixture):
    def test_61_lines_fail_and_60_pass(self):
        files = {'src/a/f.c': (
            '/* sixty */\nstatic int sixty(int x)\n{\n' + body(60) + '}\n\n'
            'static int\nsixty_one(int x, int y,\n\t  int z)\n{\n' + body(61) + '}\n'),
            'src/a/g.cpp': ('struct s {\n\tint get(int x) const override\n\t{\n'
                            + body(61, 2) + '\t}\n};\n')}
        self.assertViolations(
            self.run_check(files, {'src/a/f.c': (['f'], [])}),
            'src/a/f.c:67: function sixty_one has 61 lines (at most 60)',
            'src/a/g.cpp:2: function get has 61 lines (at most 60)')

    def test_unclosed_function_is_reported(self):
        files = {'src/a/f.c': 'int f(int x)\n{\n\treturn x;\n  }\n'}
        self.assertViolations(self.run_check(files, {'src/a/f.c': (['f'], [])}),
                              'src/a/f.c:1: function f: no closing }')


class PrivateHeaders(Fixture):
    def test_private_header_from_another_folder(self):
        files = {'src/a/priv.h': '', 'src/a/sub/z.c': '#include "a/priv.h"\n',
                 'src/util/u.h': '',
                 'src/b/use.c': '#include "util/u.h"\n#include "a/priv.h"\n'}
        self.assertViolations(
            self.run_check(files, {'src/b/use.c': (['f'], [])}),
            'src/b/use.c:2: private header src/a/priv.h of src/a/ included from outside it '
            '(#include "a/priv.h")')


if __name__ == '__main__':
    unittest.main()
