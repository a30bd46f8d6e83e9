#!/usr/bin/env python3
"""No function longer than 80 lines in the program's edges (issue 28).

The core (rt/, plant/) was cut into named steps; the edges, where a long
function grows one feature at a time, are held to the same: every function
(or method, or constructor) in tools/, drivers/ and foxglove/ has at most
MAX_LINES lines, counted from the first line of its signature to its closing
brace, comments and blank lines included (what a reader scrolls through).
Lambdas count towards the function they stand in.

The functions still being split by others are in long_functions_allowed.txt
beside this script, one `PATH NAME` a line; an entry whose function got short
(or went) fails too, so the list only shrinks.

Reads C++ as text: comments, strings and character literals are blanked,
then braces are matched. A `{` opens a function when the text before it
(since the last `;`, `{` or `}`) ends in a parameter list (and its
qualifiers, or a constructor's initialisers) and it stands in a namespace or
a class (a function's own blocks are its body).

Usage: check_function_length.py [SOURCE_DIR]   exit 0 clean, 1 too long
       check_function_length.py --self-test    the reader on made-up sources
"""
import os
import re
import sys

MAX_LINES = 80
FOLDERS = ('tools', 'drivers', 'foxglove')
ALLOWED_FILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'long_functions_allowed.txt')

# A C++ token stream is not needed; blanking these is enough to match braces.
LITERAL = re.compile(r'//[^\n]*|/\*.*?\*/|R"([^(\s]*)\(.*?\)\1"|"(?:\\.|[^"\\\n])*"|\'(?:\\.|[^\'\\\n])*\'', re.S)
SCOPE_HEAD = re.compile(r'^(template\s*<.*>\s*)?(namespace|class|struct|union|enum|extern)\b', re.S)
INITIALISER_LIST = re.compile(r'\)\s*(noexcept\s*)?:(?!:)')
# `f(...) const noexcept override -> T {`: what may follow a parameter list.
FUNCTION_END = re.compile(r'\)(\s*(const|noexcept(\s*\(.*\))?|override|final|mutable|&&?|->\s*[\w:<>,*&\s]+))*$', re.S)
CONTROL = re.compile(r'^\s*(if|for|while|switch|catch|do|else|try)\b')
NAME = re.compile(r'([~\w:<>]+(?:operator\s*[^\s(]+)?)\s*\($')


def blank(match):
    """The literal or comment as spaces, its newlines kept (line numbers stay)."""
    return re.sub(r'[^\n]', ' ', match.group(0))


def function_name(head):
    """The function's name from the text before its `{`: the word before the
    parameter list that holds no `:` initialiser list."""
    depth = 0
    # The parameter list is the first top-level (...) group after the name;
    # for a constructor with an initialiser list, cut at ` : `.
    head = re.split(r'\)\s*:(?!:)', head, maxsplit=1)[0] + ')'
    for i, c in enumerate(head):
        if c == '(':
            if depth == 0:
                m = NAME.search(head[:i].rstrip() + '(')
                if m:
                    return m.group(1)
            depth += 1
        elif c == ')':
            depth -= 1
    return '?'


def functions(text):
    """(name, first line, last line) of every function body in the text."""
    code = LITERAL.sub(blank, text)
    code = re.sub(r'^\s*#[^\n]*', blank, code, flags=re.M)  # preprocessor lines
    found = []
    stack = []  # (kind, head, index of the brace): kind scope, function, block or member initialiser
    last_break = 0  # index after the last ; { or } that ends a head
    for i, c in enumerate(code):
        if c == ';':
            last_break = i + 1
        elif c == '{':
            head = code[last_break:i]
            kind = block_kind(head, not stack or stack[-1][0] == 'scope')
            stack.append((kind, head, i))
            if kind != 'initialiser':
                last_break = i + 1
        elif c == '}' and stack:
            kind, head, start = stack.pop()
            if kind == 'function':
                first = head_start_line(code, start - len(head), head)
                last = code.count('\n', 0, i) + 1
                found.append((function_name(' '.join(head.split())), first, last))
            if kind != 'initialiser':
                last_break = i + 1
    return found


def block_kind(head, in_scope):
    """What a `{` opens, from the text before it."""
    h = head.strip()
    if not in_scope:
        return 'block'  # a function's own blocks and lambdas
    if SCOPE_HEAD.match(h):
        return 'scope'
    # `Foo(int x) : a_(x), b_{x}`: the brace of a member's initialiser.
    if INITIALISER_LIST.search(h) and re.search(r'[\w>]$', h):
        return 'initialiser'
    if (FUNCTION_END.search(h) or (INITIALISER_LIST.search(h) and h.endswith('}'))) and not CONTROL.match(h):
        return 'function'
    return 'block'  # an aggregate's initialiser


def head_start_line(code, head_index, head):
    """The line of the signature's first non-blank character."""
    m = re.match(r'\s*((public|protected|private)\s*:(?!:)\s*)*', head)
    offset = m.end()
    return code.count('\n', 0, head_index + offset) + 1


def read_allowed(path):
    allowed = set()
    if not os.path.exists(path):
        return allowed
    with open(path, encoding='utf-8') as f:
        for line in f:
            line = line.split('#', 1)[0].strip()
            if line:
                file, name = line.split()
                allowed.add((file, name))
    return allowed


def main(root, allowed_file=ALLOWED_FILE):
    allowed = read_allowed(allowed_file)
    long_ones, seen = [], set()
    for top in FOLDERS:
        for dirpath, _, names in sorted(os.walk(os.path.join(root, top))):
            for name in sorted(names):
                if not name.endswith(('.cpp', '.hpp')):
                    continue
                path = os.path.relpath(os.path.join(dirpath, name), root)
                with open(os.path.join(root, path), encoding='utf-8') as f:
                    text = f.read()
                for fn, first, last in functions(text):
                    lines = last - first + 1
                    if lines <= MAX_LINES:
                        continue
                    if (path, fn) in allowed:
                        seen.add((path, fn))
                        continue
                    long_ones.append('%s:%d: %s is %d lines (at most %d)' % (path, first, fn, lines, MAX_LINES))
    stale = ['%s: %s is allowed in %s but no longer over %d lines: take it off the list'
             % (p, fn, os.path.basename(allowed_file), MAX_LINES) for p, fn in sorted(allowed - seen)]
    for p in long_ones + stale:
        print(p)
    if long_ones or stale:
        print('%d function(s) too long, %d stale allowance(s): split it into named steps (docs/architecture.md)'
              % (len(long_ones), len(stale)))
        return 1
    print('functions short: none over %d lines in %s (%d allowed for now)' % (MAX_LINES, ', '.join(FOLDERS), len(allowed)))
    return 0


def body(lines):
    return ''.join('  x += %d;  // "}" { \'{\'\n' % i for i in range(lines))


def self_test():
    """Functions of known lengths in the shapes the reader must know: a
    function of exactly MAX_LINES passes, one line more fails, whatever its
    form (default arguments, an initialiser list with braces, a method in a
    class, lambdas and braces in strings inside); aggregates and namespaces
    are not functions; an allowance that is no longer needed fails."""
    import io
    import tempfile
    from contextlib import redirect_stdout
    inner = MAX_LINES - 2  # the signature's and the closing brace's lines
    source = ('namespace a {\nconst int table[] = {\n' + '1,\n' * 100 + '};\n'
              'int fits(int x) {\n' + body(inner) + '  return x;\n}\n'[len('  return x;\n'):] +
              'int too_long(int x,\n             int y = 0) {\n' + body(inner) + '  return x;\n}\n'
              'struct S {\n  S(int v) : v_{v}, w_(v) {\n' + body(inner + 1) + '  }\n  int v_, w_;\n'
              '  void method() const {\n    auto f = [&]() {\n' + body(inner) + '    };\n  }\n};\n}  // namespace a\n')
    expected = {'too_long': MAX_LINES + 2, 'S': MAX_LINES + 1, 'method': MAX_LINES + 2}
    with tempfile.TemporaryDirectory() as root:
        os.makedirs(os.path.join(root, 'tools'))
        with open(os.path.join(root, 'tools', 'made_up.cpp'), 'w') as f:
            f.write(source)
        found = {name: last - first + 1 for name, first, last in functions(source)}
        allowed = os.path.join(root, 'allowed.txt')
        with open(allowed, 'w') as f:
            f.write('tools/made_up.cpp too_long\ntools/made_up.cpp fits\n')
        out = io.StringIO()
        with redirect_stdout(out):
            code = main(root, allowed)
    problems = []
    if found.get('fits') != MAX_LINES:
        problems.append('fits: %s lines, expected %d' % (found.get('fits'), MAX_LINES))
    for name, lines in expected.items():
        if found.get(name) != lines:
            problems.append('%s: %s lines, expected %d' % (name, found.get(name), lines))
    if 'table' in found or 'a' in found:
        problems.append('an aggregate or a namespace counted as a function: %s' % sorted(found))
    text = out.getvalue()
    for must in ('S is', 'method is', 'fits is allowed'):
        if must not in text:
            problems.append('the report lacks "%s":\n%s' % (must, text))
    if 'too_long is' in text or code != 1:
        problems.append('the allowance of too_long not kept, or exit %d:\n%s' % (code, text))
    for p in problems:
        print(p)
    print('self-test: %s' % ('FAILED' if problems else 'the reader measures what it should'))
    return 1 if problems else 0


if __name__ == '__main__':
    if sys.argv[1:] == ['--self-test']:
        sys.exit(self_test())
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else '.'))
