#!/usr/bin/python3
"""Size limits of the sources (DEVELOPERS guide, issue 26): no file in src/ or apps/ over 800 lines
and no function over 150 lines.

    /usr/bin/python3 tests/size_check.py [ROOT]            check; exit 1 on a breach
    /usr/bin/python3 tests/size_check.py [ROOT] --list     every file and function over the limits

The files and functions that were over the limits when the check was introduced are listed in
ALLOWED with the size they had then: they may shrink (and must leave the list once under the
limit: a stale entry is a failure too, so the list only ever shrinks) but never grow. Anything
else over a limit fails.

Functions are found by a brace-matching scan that skips comments, strings and character
literals: a '{' that closes a parenthesised signature (optionally followed by const, noexcept,
override, a trailing return type, a requires clause or a member-initialiser list) and is not a
control statement (if, for, while, switch, catch) or a lambda opens a function body; its length
is the number of lines from the signature's line to the closing brace. Lambdas and local classes
count towards the function that holds them.
"""
import os
import re
import sys

FILE_LIMIT = 800
FUNCTION_LIMIT = 150
DIRS = ("src", "apps")
EXTS = (".cpp", ".hpp", ".h", ".cc", ".in")

# path -> lines, or "path:function" -> lines (the sizes when the list was last tightened; they only shrink)
ALLOWED = {
}

CONTROL = {"if", "for", "while", "switch", "catch", "return", "sizeof", "decltype", "alignof", "noexcept",
           "requires", "static_assert", "defined", "assert"}


def strip(text):
    """The text with comments, string and character literals blanked (newlines kept)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == 'R' and text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            if m:
                end = text.find(")" + m.group(1) + '"', i)
                end = n if end < 0 else end + len(m.group(1)) + 2
                out.append(re.sub(r"[^\n]", " ", text[i:end]))
                i = end
            else:
                out.append(c)
                i += 1
        elif c == '"' or (c == "'" and not (i > 0 and text[i - 1].isalnum())):
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(" " * (j - i))
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


def functions(text):
    """(name, first line, last line) of each function body in the file."""
    s = strip(text)
    line_of = []
    ln = 1
    for ch in s:
        line_of.append(ln)
        if ch == "\n":
            ln += 1
    found = []
    stack = []  # (kind, name, start line) per open brace
    for i, ch in enumerate(s):
        if ch == "{":
            kind, name, start = classify(s, i)
            inside_fn = any(k == "fn" for k, _, _ in stack)
            if kind == "fn" and not inside_fn:
                stack.append(("fn", name, line_of[start]))
            else:
                stack.append(("block", "", 0))
        elif ch == "}":
            if stack:
                kind, name, start = stack.pop()
                if kind == "fn":
                    found.append((name, start, line_of[i]))
    return found


def classify(s, brace):
    """Whether the '{' at s[brace] opens a function body; its name and where its signature starts."""
    j = brace - 1
    while j >= 0 and s[j].isspace():
        j -= 1
    head = s[max(0, j - 400):j + 1]
    # strip trailing qualifiers after the parameter list
    tail = re.sub(r"(\s*(const|noexcept(\([^()]*\))?|override|final|mutable|&|&&|->\s*[\w:<>,\s\*&]+)\s*)*$", "", head)
    tail = re.sub(r"\s*requires\s*\([^{}]*\)\s*$", "", tail)
    tail = tail.rstrip()
    if not tail.endswith(")"):
        return "block", "", brace
    # the matching '('
    depth, k = 0, len(tail) - 1
    while k >= 0:
        if tail[k] == ")":
            depth += 1
        elif tail[k] == "(":
            depth -= 1
            if depth == 0:
                break
        k -= 1
    if k < 0:
        return "block", "", brace
    before = tail[:k].rstrip()
    if before.endswith("]") or before.endswith("]<>"):  # lambda
        return "block", "", brace
    m2 = re.search(r"((?:[\w~]+(?:<[^<>]*>)?::)*(?:operator\s*[^\s(]+|[~\w]+(?:<[^<>]*>)?))\s*$", before)
    if not m2:
        return "block", "", brace
    name = m2.group(1)
    word = name.split("::")[-1]
    if word in CONTROL or re.fullmatch(r"[\d_]+", word):
        return "block", "", brace
    start = (j - len(head) + 1) + (m2.start() if m2 else 0)
    return "fn", name, max(0, start)


def scan(root):
    over = {}
    for d in DIRS:
        for base, _, files in os.walk(os.path.join(root, d)):
            for f in sorted(files):
                if not f.endswith(EXTS):
                    continue
                p = os.path.join(base, f)
                rel = os.path.relpath(p, root)
                text = open(p, encoding="utf-8", errors="replace").read()
                n = text.count("\n") + (0 if text.endswith("\n") or not text else 1)
                if n > FILE_LIMIT:
                    over[rel] = n
                for name, a, b in functions(text):
                    if b - a + 1 > FUNCTION_LIMIT:
                        key = f"{rel}:{name}"
                        over[key] = max(over.get(key, 0), b - a + 1)
    return over


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    root = args[0] if args else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    over = scan(root)
    if "--list" in sys.argv:
        for k, v in sorted(over.items(), key=lambda kv: -kv[1]):
            print(f"{v:6d}  {k}")
        return 0
    bad = []
    for k, v in sorted(over.items()):
        if k not in ALLOWED:
            limit = FUNCTION_LIMIT if ":" in k else FILE_LIMIT
            bad.append(f"{k}: {v} lines, over the limit of {limit}")
        elif v > ALLOWED[k]:
            bad.append(f"{k}: {v} lines, grew past the {ALLOWED[k]} it had when the limit came in")
    for k in sorted(ALLOWED):
        if k not in over:
            bad.append(f"{k}: now within the limit; remove it from ALLOWED in tests/size_check.py")
    for b in bad:
        print("size_check: " + b)
    print(f"size_check: {len(over)} over the limits ({len(ALLOWED)} allowed, shrinking), {len(bad)} breaches")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
