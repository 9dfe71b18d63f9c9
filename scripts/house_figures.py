#!/usr/bin/python3
"""The house's figures (docs/design.md): the longest .c file, the longest
function, stages/'s share of src/ (lines of .c and .h), and the circles of
the include-and-call graph of src/.

A .c file points at the .c files whose functions it calls and at the
headers it includes, a header at the headers it includes (so only calls
close a circle between .c files). A circle is a strongly connected set of more than one node.

usage: scripts/house_figures.py [SRC] [--check]   (default: src)
--check: exit 1 when the house breaks its limits (docs/design.md): a .c file
over 700 lines, a function over 100, stages/ over 30 %, a circle, an arrow
that runs up a layer."""
import os
import re
import sys

CALL = re.compile(r'\b(\w+)\s*\(')
INC = re.compile(r'^#include "([\w/]+)\.h"')


def sources(src):
    for d, _, fs in sorted(os.walk(src)):
        for f in sorted(fs):
            if f.endswith(('.c', '.h')):
                yield os.path.join(d, f)


def functions(lines):
    """(name, lines, static) of every function defined at column 0 in lines."""
    out, i = [], 0
    while i < len(lines):
        m = re.match(r'^(?:static\s+)?(?:inline\s+)?[A-Za-z_][\w \*]*?\b(\w+)\s*\(', lines[i])
        if m and not lines[i].rstrip().endswith(';') and not lines[i].startswith(('#', 'typedef')):
            j = i
            while j < len(lines) and not lines[j].startswith('{'):
                if lines[j].rstrip().endswith(';'):
                    break
                j += 1
            if j < len(lines) and lines[j].startswith('{'):
                k = j
                while k < len(lines) and not lines[k].startswith('}'):
                    k += 1
                out.append((m.group(1), k - i + 1, lines[i].startswith('static')))
                i = k
        i += 1
    return out


def circles(graph):
    """Tarjan's strongly connected components of more than one node."""
    index, low, stack, on, out = {}, {}, [], set(), []
    sys.setrecursionlimit(10000)

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v), on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))
    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def main():
    args = [a for a in sys.argv[1:] if a != '--check']
    src = args[0] if args else 'src'
    text = {}
    for p in sources(src):
        with open(p, encoding='utf-8') as f:
            text[os.path.relpath(p, src)] = f.read().split('\n')
    node = lambda p: os.path.splitext(p)[0]
    lines = {p: len(t) - (t[-1] == '') for p, t in text.items()}
    total = sum(lines.values())
    stages = sum(n for p, n in lines.items() if p.startswith('stages/'))
    cfiles = [(n, p) for p, n in lines.items() if p.endswith('.c')]
    longest_file = max(cfiles)
    funcs = [(n, name, p) for p, t in text.items() if p.endswith('.c') for name, n, _ in functions(t)]
    funcs.sort(reverse=True)
    defined, twice = {}, set()
    for p, t in text.items():
        if p.endswith('.c'):
            for name, _, static in functions(t):
                if static:
                    continue
                if name in defined:
                    twice.add(name)   # another build's version (core/comm.c, mpi/comm_mpi.c)
                defined[name] = node(p)
    for name in twice:
        del defined[name]
    key = lambda p: node(p) if p.endswith('.c') else p
    graph = {key(p): set() for p in text}
    for p, t in text.items():
        for ln in t:
            m = INC.match(ln)
            if m and m.group(1) + '.h' in text:
                graph[key(p)].add(m.group(1) + '.h')
    for p, t in text.items():
        if p.endswith('.c'):
            for ln in t:
                for name in CALL.findall(ln):
                    b = defined.get(name)
                    if b:
                        graph[node(p)].add(b)
    for a in graph:
        graph[a].discard(a)
    over = [f'{p} {n}' for n, p in sorted(cfiles, reverse=True) if n > 700]
    print(f'longest file: {longest_file[1]} {longest_file[0]} lines')
    print(f'files over 700 lines: {len(over)}' + ''.join(f'\n  {o}' for o in over))
    print(f'longest function: {funcs[0][1]} ({funcs[0][2]}) {funcs[0][0]} lines')
    big = [f for f in funcs if f[0] > 100]
    print(f'functions over 100 lines: {len(big)}' + ''.join(f'\n  {f[1]} ({f[2]}) {f[0]}' for f in big))
    print(f'stages/ share of src/: {100 * stages / total:.1f} % ({stages} of {total} lines of .c and .h)')
    if os.environ.get('HOUSE_EDGES'):
        for a in sorted(graph):
            if a.startswith(os.environ['HOUSE_EDGES']):
                print(a, '->', ' '.join(sorted(graph[a])))
    circ = circles(graph)
    print(f'circles in the include-and-call graph: {len(circ)}')
    for c in circ:
        print('  ' + ' <-> '.join(c))
    layer = {'core': 0, 'mpi': 0, 'io': 1, 'optics': 1, 'ops': 2, 'solve': 3, 'stages': 4, 'sim': 4,
             'eval': 4, 'report': 5, 'app': 5.5, 'cli': 6}   # app/ calls report/, never back
    up = sorted(f'{a} -> {b}' for a, es in graph.items() for b in es
                if layer.get(a.split('/')[0], 9) < layer.get(b.split('/')[0], 9))
    print(f'arrows that run up a layer: {len(up)}' + ''.join(f'\n  {u}' for u in up))
    broken = over or big or stages > 0.3 * total or circ or up
    if '--check' in sys.argv and broken:
        sys.exit('the house breaks its limits (docs/design.md, "Limits the house keeps")')


if __name__ == '__main__':
    main()
