#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Lengths (lines) of the function bodies in C++ files: a brace-matching counter.

A function is a top-level `{ ... }` block (namespace blocks are entered, class/struct bodies
too) whose opening brace follows a `)` (possibly with qualifiers such as const, override,
noexcept, or a trailing return type / member-initialiser list). Lambdas and nested blocks are
counted as part of the enclosing function. Comments, strings and preprocessor lines are skipped.

  tools/function_lengths.py [--top N] [--max L] DIR_OR_FILE...
Prints the longest functions; with --max, exits 1 if any is longer than L lines."""
import argparse, os, re, sys

def strip(text):
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith('//', i):
            j = text.find('\n', i); j = n if j < 0 else j
            i = j
        elif text.startswith('/*', i):
            j = text.find('*/', i + 2); j = n if j < 0 else j + 2
            out.append('\n' * text.count('\n', i, j)); i = j
        elif c == '"' or c == "'":
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == '\\' else 1
            out.append(c + c); i = j + 1
        else:
            out.append(c); i += 1
    lines = ''.join(out).split('\n')
    return '\n'.join('' if l.lstrip().startswith('#') else l for l in lines)

def functions(path):
    src = strip(open(path, encoding='utf-8', errors='replace').read())
    res, stack, i, line = [], [], 0, 1   # stack entries: (kind, start_line, name)
    head_start = 0
    for m in re.finditer(r'[{};\n]', src):
        ch = m.group()
        if ch == '\n':
            line += 1; continue
        if ch == ';':
            if not stack or stack[-1][0] != 'func': head_start = m.end()
            continue
        if ch == '{':
            head = src[head_start:m.start()]
            if stack and stack[-1][0] in ('func', 'inner'):
                stack.append(('inner', line, ''))
            else:
                h = ' '.join(head.split())
                if re.search(r'\b(namespace|class|struct|union|enum)\b[^()]*$', h) or h.endswith('=') or not h:
                    stack.append(('scope', line, ''))
                elif re.search(r'\)[^()]*$', h) or re.search(r'\)\s*:', h):
                    nm = re.findall(r'([~\w:<>]+)\s*\(', h)
                    stack.append(('func', line, nm[0] if nm else h[:40]))
                else:
                    stack.append(('scope', line, ''))
            head_start = m.end()
        else:  # '}'
            if stack:
                kind, start, name = stack.pop()
                if kind == 'func':
                    res.append((line - start + 1, name, path, start))
            head_start = m.end()
    return res

def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('paths', nargs='+')
    ap.add_argument('--top', type=int, default=10)
    ap.add_argument('--max', type=int, default=0)
    a = ap.parse_args()
    files = []
    for p in a.paths:
        if os.path.isdir(p):
            for root, _, names in os.walk(p):
                files += [os.path.join(root, f) for f in names if f.endswith(('.h', '.cpp', '.hpp', '.cc'))]
        else:
            files.append(p)
    allf = sorted((f for p in sorted(files) for f in functions(p)), reverse=True)
    for n, name, path, start in allf[:a.top]:
        print(f'{n:5d}  {name}  {path}:{start}')
    print(f'{len(allf)} functions in {len(files)} files; longest {allf[0][0] if allf else 0} lines')
    if a.max and allf and allf[0][0] > a.max:
        sys.exit(1)

main()
