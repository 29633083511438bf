#!/usr/bin/env python3
"""Prints the cycles in the module include graph of src/ and exits 1 if any.

A module is a file's path under src/ less its extension (scene/shape is
shape.c and shape.h). Module A depends on module B when a file of A includes
B's header, or includes a header that declares a function B.c defines: a
header that speaks for two .c files (a.h declaring b.c's functions too) hides
a dependency that the bare #include lines do not show. --plain counts the
#include lines only.

  python3 tools/include-cycles.py [--plain] [--why] [SRC_DIR]

--why shows, under each cycle, what makes each of its edges.
"""
import collections
import os
import re
import sys

EXTS = ('.c', '.h', '.cpp', '.hpp')
INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"', re.M)
NAME_BEFORE_PAREN = re.compile(r'\b([A-Za-z_]\w*)\s*\(')


def strip(text):
    """Code without comments, literals or preprocessor lines."""
    text = re.sub(r'//[^\n]*|/\*.*?\*/|"(?:\\.|[^"\\\n])*"|\'(?:\\.|[^\'\\\n])*\'',
                  lambda m: ' ' if m.group(0)[0] == '/' else '""', text, flags=re.S)
    text = re.sub(r'^\s*#(?:[^\n]*\\\n)*[^\n]*', ' ', text, flags=re.M)
    return re.sub(r'extern\s*""\s*\{', ' ', text)


def top_level(text):
    """(head, has_body) for each top-level declaration or definition."""
    depth, start, out = 0, 0, []
    for i, ch in enumerate(text):
        if ch == '{':
            if depth == 0:
                out.append((text[start:i], True))
            depth += 1
        elif ch == '}':
            depth = max(depth - 1, 0)  # the close of an extern "C" block
            if depth == 0:
                start = i + 1
        elif ch == ';' and depth == 0:
            out.append((text[start:i], False))
            start = i + 1
    return out


def function_name(head):
    head = head.strip()
    if not head or re.match(r'(typedef|struct|union|enum|namespace|static)\b', head):
        return None
    if '=' in head.split('(')[0] or re.search(r'\(\s*\*', head):
        return None
    m = NAME_BEFORE_PAREN.search(head)
    return m.group(1) if m else None


def main():
    args = [a for a in sys.argv[1:] if not a.startswith('--')]
    plain, verbose = '--plain' in sys.argv[1:], '--why' in sys.argv[1:]
    src = args[0] if args else os.path.join(os.path.dirname(__file__), '..', 'src')
    src = os.path.normpath(src)
    files = {}
    for root, _, names in os.walk(src):
        for n in names:
            if n.endswith(EXTS):
                path = os.path.join(root, n)
                with open(path, encoding='utf-8', errors='replace') as f:
                    files[os.path.relpath(path, src)] = f.read()

    def module(rel):
        return os.path.splitext(rel)[0]

    defined, declared = {}, {}
    for rel, text in files.items():
        for head, body in top_level(strip(text)):
            name = function_name(head)
            if not name:
                continue
            if body and not rel.endswith(('.h', '.hpp')):
                defined.setdefault(name, module(rel))
            elif not body:
                declared.setdefault(rel, collections.Counter())[name] += 1

    def includes(rel):
        for inc in INCLUDE.findall(files[rel]):
            for cand in (inc, os.path.join(os.path.dirname(rel), inc)):
                cand = os.path.normpath(cand)
                if cand in files:
                    yield cand
                    break

    def reachable(rel):
        seen, todo = set(), list(includes(rel))
        while todo:
            h = todo.pop()
            if h not in seen:
                seen.add(h)
                todo.extend(includes(h))
        return seen

    graph, why = {}, {}
    for rel in files:
        m = module(rel)
        graph.setdefault(m, set())
        for h in includes(rel):
            why.setdefault((m, module(h)), []).append(f'{rel} includes {h}')
        if not plain:
            # What this file uses of the functions its headers, direct or
            # not, declare for another module (its own prototypes too).
            # A name counts where it appears more often than it is declared.
            words = collections.Counter(re.findall(r'\w+', strip(files[rel])))
            used = {n for n, k in words.items() if k > declared.get(rel, {}).get(n, 0)}
            for h in reachable(rel) | {rel}:
                for n in sorted(set(declared.get(h, ())) & used):
                    if n in defined:
                        why.setdefault((m, defined[n]), []).append(
                            f'{rel} calls {n} ({h})')
        graph[m] |= {b for a, b in why if a == m and b != m}

    cycles = strongly_connected(graph)
    for scc in cycles:
        if verbose:
            path = shortest_cycle(graph, scc)
            for a, b in zip(path, path[1:]):
                print(f'  {a} -> {b}: ' + '; '.join(why[(a, b)][:3]))
        print('cycle: ' + ' -> '.join(shortest_cycle(graph, scc)) +
              ('' if len(scc) == 2 else '  (in a knot of ' + ' '.join(scc) + ')'))
    print(f'{len(cycles)} cycle(s) among {len(graph)} modules')
    return 1 if cycles else 0


def strongly_connected(graph):
    """Tarjan's strongly connected components of more than one module."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            scc = []
            while True:
                w = stack.pop()
                on.discard(w)
                scc.append(w)
                if w == v:
                    break
            if len(scc) > 1:
                out.append(sorted(scc))

    sys.setrecursionlimit(10000)
    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(out)


def shortest_cycle(graph, scc):
    """The shortest cycle through the component's first module (breadth first)."""
    start, members = scc[0], set(scc)
    prev, queue = {start: None}, [start]
    for v in queue:
        for w in sorted(graph[v] & members):
            if w == start:
                path = [v]
                while prev[path[-1]] is not None:
                    path.append(prev[path[-1]])
                return [start] + path[::-1][1:] + [start] if len(path) > 1 else [start, v, start]
            if w not in prev:
                prev[w] = v
                queue.append(w)
    return scc


if __name__ == '__main__':
    sys.exit(main())
