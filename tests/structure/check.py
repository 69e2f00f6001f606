#!/usr/bin/env python3
"""The structure of src/: what the compiler does not check and a reviewer misses in a diff.

Usage: tests/structure/check.py ROOT (--nm-output FILE | OBJECT...)
  ROOT          the source tree (its src/ and include/ are read; tests/, tools/, fuzz/ and
                examples/ are not checked)
  OBJECT        archives or object files built from src/ (meson: libmvod.a, and the mvod
                executable's own objects, src/main.c and src/cli/); `nm -A` is run on them
  --nm-output   that output of `nm -A`, saved in FILE, instead of running nm (for the tests)

Prints one line per violation, `path:line: what`, and exits 1; exits 0, silent, when src/ is
clean; 2 on a usage error or when the objects hold nothing of src/.

Terms. A module is one source file and the header of the same stem in the same folder
(src/vo/map.c + src/vo/map.h is module src/vo/map; a header alone, src/vo/types.h, is module
src/vo/types). Each public header include/mvod/X.h is a module of its own, include/mvod/X. A
module's folder is the folder its files are in (src/vo/map -> src/vo, src/pipeline -> src;
src/vo/core/frame -> src/vo/core: a subfolder is a folder of its own). A module depends on
another through three kinds of edge:

  include  a file of A has `#include "..."` of a file of B, resolved as the compiler does here:
           the including file's own folder first, then include/, then src/. System headers
           <...> and generated headers that resolve into neither (the LCM types) are ignored.
  call     an object of A has an undefined symbol (function or data) that an object of B
           defines (`nm -A`: U against T, D, B, R, G, S, C, i). Weak definitions (W, V, u) are
           not counted: they are C++ inline and template instantiations that several shims
           carry, and name no module. Objects are mapped back to their source by meson's
           naming, the path with / as _ (libmvod.a.p/src_vo_map.c.o is src/vo/map.c).
  header   a file of A includes a public header include/mvod/X.h that declares what a module B
           of another folder defines (B implements X.h; "declares": the header names a symbol
           B defines, outside comments). Then A depends on B, not only on the header:
           src/sink/sink_eval.c uses struct mvod_run_summary from include/mvod/pipeline.h, the
           pipeline's own interface, which src/pipeline.c implements and which calls
           src/sink/*; that is a circle, though no include and no call closes it. Why this
           rule: a public header as a node of its own could never close a circle (it includes
           only other public headers), so a module could hand its types to its own callers
           through it unseen. Why only across folders: the modules of one folder that
           implement one public header between them (src/capture/source.c and capture.c,
           both for include/mvod/capture.h) each include it, and that is no circle; inside a
           folder the include and call edges see circles well enough. A header that declares
           nothing anyone defines (include/mvod/image.h: types only) is a node only. Hence the
           way to share a module's types with the modules it calls is a types-only header.
           Only a module's direct includes count; public headers' includes of one another do
           not pass the dependency on.

The rules, one line printed per violation:

 1. No circle of modules (the include, call and header edges together). Printed, for each
    strongly connected component of the module graph: its shortest circle through its first
    module, then through the first module not on a printed circle yet, until every module of
    the component is on one (a single circle would hide the others: a component is often
    several circles through one module). Each circle is one line: the chain of modules, each
    edge with its kind and one example (the include, the symbol and where the calling file
    first names it, or the public header and a symbol it declares), then the component's
    modules. Why: a circle makes its modules one unit that can be neither tested, nor
    changed, nor understood one by one.
 2. No circle of folders: the same graph with each module collapsed to its folder, printed the
    same way; edges into include/mvod (declarations) are not counted. Why: folders are the
    units the tree is read, owned and layered in.
 3. The layers of src/vo (LAYERS below, top first): an edge (of any kind) from one folder of
    the table to another must go down, to a lower rank. So a mode (twoview, map) may use the
    parts and the core but not the other mode, a part (frontend, geom, optim) only the core,
    and the core none of them. A folder of the table that does not exist yet checks nothing.
    Header edges count here too: a part including include/mvod/vo.h depends on src/vo/vo.c,
    the facade, which implements it; the types the parts share belong in a types-only header.
 4. No function longer than MAX_FUNCTION_LINES lines in src/ (C and C++). A function's lines
    are those strictly between its opening and closing braces, both on lines of their own: the
    house style (.clang-format: BreakBeforeBraces Linux) puts a function's `{` alone on the line
    after its signature and its `}` alone at the same indentation, column 0 (one tab for a C++
    member function defined inside its class). A `{` alone on its line counts only after a line
    ending the signature (`)`, then const, noexcept, override or final), so initialisers
    (`static const int t[] = {`), `extern "C" {`, struct bodies and lambdas
    (`return mvod_guarded([&] {`, part of their function's body) are not functions. Why: a
    long function does several things that no test, name or comment separates.
 5. A header under src/F/ (F the top-level folder: capture, vo, calib, ...) is included only by
    files under src/F/, except the shared helpers of src/util/ and the pairs of
    PRIVATE_HEADER_EXCEPTIONS (src/main.c and src/pipeline.c, directly in src/, are under no
    src/F/; a header directly in src/ is no folder's). Why: what another folder needs is that
    folder's interface (include/mvod/), not its insides.
"""
import argparse
import os
import re
import subprocess
import sys
from collections import defaultdict, deque, namedtuple

# Rule 3: the layers of src/vo, top first; an edge between two of these folders goes down.
LAYERS = [
    ('facade', ['src/vo']),                                        # vo.c
    ('modes', ['src/vo/twoview', 'src/vo/map']),
    ('parts', ['src/vo/frontend', 'src/vo/geom', 'src/vo/optim']),
    ('core', ['src/vo/core']),                                     # the core types
]

# Rule 4.
MAX_FUNCTION_LINES = 60

# Rule 5: folders whose headers any file of src/ may include.
SHARED_HEADER_FOLDERS = ['src/util']
# Rule 5: (including file, header) -> why that file may include that private header of another
# folder, e.g. ('src/cli/view.c', 'src/ipc/lcm_log.h'): '...'. Empty: the three crossings of
# src/ when this check was written (src/main.c -> src/cli/cli.h, src/cli/view.c ->
# src/ipc/lcm_log.h and src/ipc/log_check.h) are for the restructure to resolve, not allowed.
PRIVATE_HEADER_EXCEPTIONS = {}

SOURCE_EXTENSIONS = ('.c', '.cpp')
HEADER_EXTENSIONS = ('.h', '.hpp')
# nm's types of a symbol an object defines for others to use (rule 1, call edges).
DEFINING_TYPES = set('TDBRGSCi')
EDGE_KINDS = ('include', 'call', 'header')  # in the order an example is chosen

INCLUDE_RE = re.compile(r'^\s*#\s*include\s*"([^"]+)"')
# nm -A: "archive:member:value type name" or "object:value type name" (value absent for U).
NM_LINE_RE = re.compile(r'^(.*):\s*(?:[0-9a-fA-F]+\s+)?(\S)\s+(\S+)$')
# The line before a function's `{`: the end of its signature.
SIGNATURE_END_RE = re.compile(r'\)\s*(?:(?:const|noexcept|override|final)\s*)*$')
FUNCTION_NAME_RE = re.compile(
    r'(operator\s*\(\)|operator\s*[^\s(]+|~?[A-Za-z_]\w*(?:::~?[A-Za-z_]\w*)*)\s*\(')
ATTRIBUTE_RE = re.compile(r'__attribute__\s*\(\(.*?\)\)')

# One reason for an edge: its kind, where it is (path, line) and what it is.
Evidence = namedtuple('Evidence', 'kind path line what')
Violation = namedtuple('Violation', 'path line what')


def module_of(path):
    """The module a file belongs to: its path without the extension."""
    return os.path.splitext(path)[0]


def folder_of(module):
    return os.path.dirname(module)


def strip_comments(text):
    """text with comments blanked (newlines kept, so line numbers stay)."""
    def blank(m):
        return re.sub(r'[^\n]', ' ', m.group(0))
    return re.sub(r'/\*.*?\*/|//[^\n]*', blank, text, flags=re.S)


class Tree:
    """The C and C++ files of src/ and the public headers, read once."""

    def __init__(self, root):
        self.root = root
        self.text = {}  # relative path -> contents
        for top in ('src', 'include/mvod'):
            for folder, dirs, files in os.walk(os.path.join(root, top)):
                dirs.sort()
                for name in sorted(files):
                    if name.endswith(SOURCE_EXTENSIONS + HEADER_EXTENSIONS):
                        path = os.path.relpath(os.path.join(folder, name), root)
                        with open(os.path.join(root, path), encoding='utf-8') as f:
                            self.text[path] = f.read()

    def src_files(self):
        return [p for p in self.text if p.startswith('src/')]

    def public_headers(self):
        return [p for p in self.text if p.startswith('include/')]

    def lines(self, path):
        return self.text[path].split('\n')

    def resolve(self, path, name):
        """The file `#include "name"` in path reads, or None when outside the tree."""
        for folder in (os.path.dirname(path), 'include', 'src'):
            candidate = os.path.normpath(os.path.join(folder, name))
            if candidate in self.text:
                return candidate
        return None

    def includes(self, path):
        """(line, name as written, resolved path) of each include of path that is in the tree."""
        for number, line in enumerate(self.lines(path), 1):
            m = INCLUDE_RE.match(line)
            target = m and self.resolve(path, m.group(1))
            if target:
                yield number, m.group(1), target

    def first_use(self, path, symbol):
        """The first line of path that names symbol (1 when it does not: a mangled name)."""
        pattern = re.compile(r'\b' + re.escape(symbol) + r'\b')
        for number, line in enumerate(self.lines(path), 1):
            if pattern.search(line):
                return number
        return 1


class Symbols:
    """Who defines and who needs which symbol, per source file of src/, from nm -A."""

    def __init__(self, tree, nm_output):
        by_object_name = {p.replace('/', '_') + '.o': p for p in tree.src_files()}
        self.defined_by = defaultdict(set)  # symbol -> source files
        self.undefined = defaultdict(set)   # source file -> symbols
        for line in nm_output.splitlines():
            m = NM_LINE_RE.match(line)
            if not m:
                continue
            member, kind, symbol = m.groups()
            source = by_object_name.get(re.split(r'[/:]', member)[-1])
            if source is None:
                continue
            if kind == 'U':
                self.undefined[source].add(symbol)
            elif kind in DEFINING_TYPES:
                self.defined_by[symbol].add(source)
        self.found = bool(self.defined_by or self.undefined)


def module_edges(tree, symbols):
    """(A, B) -> [Evidence] for every edge of rule 1 between two modules A != B."""
    edges = defaultdict(list)

    def add(a, b, evidence):
        if a != b:
            edges[(a, b)].append(evidence)

    implementers = public_header_implementers(tree, symbols)
    for path in tree.src_files() + tree.public_headers():
        a = module_of(path)
        for line, name, target in tree.includes(path):
            add(a, module_of(target), Evidence('include', path, line, f'"{name}"'))
            if not path.startswith('src/'):
                continue
            for b, symbol in sorted(implementers.get(target, {}).items()):
                if folder_of(b) != folder_of(a):
                    add(a, b, Evidence('header', path, line,
                                       f'"{name}" declares {symbol}, defined in {b}'))
    for path, needed in symbols.undefined.items():
        for symbol in sorted(needed):
            for definer in sorted(symbols.defined_by.get(symbol, ())):
                add(module_of(path), module_of(definer), Evidence(
                    'call', path, tree.first_use(path, symbol), symbol))
    return edges


def public_header_implementers(tree, symbols):
    """include/mvod/X.h -> {module: one symbol it declares that the module defines}."""
    result = {}
    for header in tree.public_headers():
        names = set(re.findall(r'\b[A-Za-z_]\w*\b', strip_comments(tree.text[header])))
        result[header] = {}
        for symbol in sorted(names):
            for definer in sorted(symbols.defined_by.get(symbol, ())):
                result[header].setdefault(module_of(definer), symbol)
    return result


def example(evidences):
    """The one evidence shown for an edge: an include if there is one, else a call, else a
    header edge; the first in the tree of that kind."""
    return min(evidences, key=lambda e: (EDGE_KINDS.index(e.kind), e.path, e.line))


def strongly_connected(graph):
    """The strongly connected components of graph (node -> successors) with two nodes or more,
    each sorted, in sorted order. The graphs here have some hundred nodes: reachability from
    every node is fast enough and plainly right."""
    def reachable(start):
        seen, todo = set(), [start]
        while todo:
            for nxt in graph.get(todo.pop(), ()):
                if nxt not in seen:
                    seen.add(nxt)
                    todo.append(nxt)
        return seen

    reach = {node: reachable(node) for node in graph}
    components = set()
    for node in graph:
        members = frozenset(m for m in reach[node] if node in reach.get(m, ()))
        if len(members) > 1:
            components.add(tuple(sorted(members)))
    return sorted(components)


def shortest_cycle(graph, start, members):
    """The shortest cycle from start back to start within members: [start, ..., start]."""
    parent = {start: None}
    queue = deque([start])
    while queue:
        node = queue.popleft()
        for nxt in sorted(graph[node] & members):
            if nxt == start:
                path = [node]
                while parent[path[-1]] is not None:
                    path.append(parent[path[-1]])
                return path[::-1] + [start]
            if nxt not in parent:
                parent[nxt] = node
                queue.append(nxt)
    raise AssertionError('a strongly connected component without a cycle')


def circles(edges, what):
    """The circles the graph edges ((A, B) -> [Evidence]) makes: for each strongly connected
    component, shortest cycles until each of its nodes is on one (one would hide the others:
    a component is often several circles through one node). One violation per cycle."""
    graph = defaultdict(set)
    for a, b in edges:
        graph[a].add(b)
    violations = []
    for members in strongly_connected(graph):
        uncovered = list(members)
        while uncovered:
            cycle = shortest_cycle(graph, uncovered[0], set(members))
            uncovered = [m for m in uncovered if m not in cycle]
            steps = []
            for a, b in zip(cycle, cycle[1:]):
                e = example(edges[(a, b)])
                steps.append(f'{a} --{e.kind} {e.what} ({e.path}:{e.line})-->')
            first = example(edges[(cycle[0], cycle[1])])
            violations.append(Violation(first.path, first.line, (
                f'{what} circle: {" ".join(steps)} {cycle[0]} '
                f'(component of {len(members)} {what}s: {", ".join(members)})')))
    return violations


def folder_edges(edges):
    """Rule 2's graph: the module edges between folders, none into include/mvod."""
    folders = defaultdict(list)
    for (a, b), evidences in edges.items():
        fa, fb = folder_of(a), folder_of(b)
        if fa != fb and fb != 'include/mvod':
            folders[(fa, fb)].extend(evidences)
    return folders


def layer_violations(folders):
    rank = {folder: (number, name)
            for number, (name, members) in enumerate(LAYERS) for folder in members}
    violations = []
    for (fa, fb), evidences in sorted(folders.items()):
        if fa in rank and fb in rank and rank[fb][0] <= rank[fa][0]:
            e = example(evidences)
            violations.append(Violation(e.path, e.line, (
                f'layer: {fa} ({rank[fa][1]}) may not depend on {fb} ({rank[fb][1]}), '
                f'only on lower layers ({e.kind} {e.what})')))
    return violations


def functions(lines):
    """(name, line of the name, lines of the body) of each function defined in lines."""
    for i, text in enumerate(lines):
        m = re.fullmatch(r'(\s*)\{\s*', text)
        if not m or i == 0 or not SIGNATURE_END_RE.search(lines[i - 1]):
            continue
        name, name_line = function_name(lines, i)
        close = next((j for j in range(i + 1, len(lines))
                      if lines[j].startswith(m.group(1) + '}')), None)
        yield name, name_line, None if close is None else close - i - 1


def function_name(lines, brace):
    """The name of the function whose `{` is at lines[brace], and its line (1-based)."""
    start = brace - 1
    while start > 0 and not re.search(r'[;{}]\s*$|\*/\s*$|^\s*(#|//)|^\s*$', lines[start - 1]):
        start -= 1
    signature = ATTRIBUTE_RE.sub('', '\n'.join(lines[start:brace]))
    m = FUNCTION_NAME_RE.search(signature)
    if not m:
        return '?', brace + 1
    return m.group(1), start + 1 + signature.count('\n', 0, m.start())


def long_functions(tree):
    violations = []
    for path in tree.src_files():
        for name, line, length in functions(tree.lines(path)):
            if length is None:
                violations.append(Violation(path, line, (
                    f'function {name}: no closing }} under its opening {{ (house style)')))
            elif length > MAX_FUNCTION_LINES:
                violations.append(Violation(path, line, (
                    f'function {name} has {length} lines (at most {MAX_FUNCTION_LINES})')))
    return violations


def top_folder(path):
    """src/F for a path under src/F/, None for one directly in src/ or outside src/."""
    parts = path.split('/')
    return '/'.join(parts[:2]) if parts[0] == 'src' and len(parts) > 2 else None


def private_header_violations(tree):
    violations = []
    for path in tree.src_files():
        for line, name, target in tree.includes(path):
            owner = top_folder(target)
            if (owner is None or owner in SHARED_HEADER_FOLDERS or top_folder(path) == owner
                    or (path, target) in PRIVATE_HEADER_EXCEPTIONS):
                continue
            violations.append(Violation(path, line, (
                f'private header {target} of {owner}/ included from outside it '
                f'(#include "{name}")')))
    return violations


def check(root, nm_output):
    """The violations of the five rules, in that order; None when nm_output has no object of
    src/."""
    tree = Tree(root)
    symbols = Symbols(tree, nm_output)
    if not symbols.found:
        return None
    edges = module_edges(tree, symbols)
    folders = folder_edges(edges)
    return (circles(edges, 'module') + circles(folders, 'folder') + layer_violations(folders)
            + sorted(long_functions(tree)) + sorted(private_header_violations(tree)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('root')
    parser.add_argument('objects', nargs='*')
    parser.add_argument('--nm-output')
    args = parser.parse_args()
    if bool(args.objects) == bool(args.nm_output):
        parser.error('give either OBJECT... or --nm-output FILE')
    if args.nm_output:
        with open(args.nm_output, encoding='utf-8') as f:
            nm_output = f.read()
    else:
        nm = subprocess.run(['nm', '-A'] + args.objects, capture_output=True, text=True)
        if nm.returncode != 0:
            print(f'check.py: nm -A failed: {nm.stderr.strip()}', file=sys.stderr)
            return 2
        nm_output = nm.stdout
    violations = check(args.root, nm_output)
    if violations is None:
        print(f'check.py: no object built from {args.root}/src in the nm output',
              file=sys.stderr)
        return 2
    for v in violations:
        print(f'{v.path}:{v.line}: {v.what}')
    return 1 if violations else 0


if __name__ == '__main__':
    sys.exit(main())
