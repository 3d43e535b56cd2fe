"""The function bodies of a C++ file, found lexically (issue 33, part 6).

A function here is a brace-delimited body at namespace or class scope whose
head (the text since the previous ';', '{' or '}' at that scope) has a
parenthesised parameter list and is no initialiser (no '=' outside
parentheses), no class, struct, union, enum or namespace and no
`extern "C"`: free functions, member functions defined in or out of their
class, constructors with their initialiser lists, operators, templates, and
macro-made bodies such as GoogleTest's TEST(Suite, Name) { ... }. Lambdas and
local classes inside a body belong to it. Its length runs from the first line
of its head to the line of its closing brace, as check_function_size.py counts
a Python def from its first decorator.

Comments, string and character literals (raw strings too) and preprocessor
lines are blanked first, keeping the line breaks, so that braces inside them
do not count. The scanner needs no compiler and no include path: it reads a
file as text, so a construct it misreads (a brace inside a macro's argument
at namespace scope, say) can only hide or merge bodies, never invent lines.
"""
import re

_WORD = re.compile(r"[A-Za-z_]\w*")
_SCOPE_WORDS = {"namespace", "class", "struct", "union", "enum"}


def blank(text):
    """text with comments, literals and preprocessor lines turned to spaces (newlines kept)."""
    out = []
    i, n = 0, len(text)
    line_start = True
    while i < n:
        c = text[i]
        if line_start and c in " \t":
            out.append(c)
            i += 1
            continue
        if line_start and c == "#":  # a preprocessor line, with its continuations
            while i < n and text[i] != "\n":
                if text[i] == "\\" and i + 1 < n and text[i + 1] == "\n":
                    out.append(" \n")
                    i += 2
                    continue
                out.append(" ")
                i += 1
            continue
        line_start = c == "\n"
        if text.startswith("//", i):
            while i < n and text[i] != "\n":
                out.append(" ")
                i += 1
            continue
        if text.startswith("/*", i):
            end = text.find("*/", i + 2)
            end = n if end < 0 else end + 2
            out.append(re.sub(r"[^\n]", " ", text[i:end]))
            i = end
            continue
        raw = re.match(r'(?:u8|[uUL])?R"([^(\s]{0,16})\(', text[i:i + 24])
        if raw and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            close = ")" + raw.group(1) + '"'
            end = text.find(close, i + raw.end())
            end = n if end < 0 else end + len(close)
            out.append(re.sub(r"[^\n]", " ", text[i:end]))
            i = end
            continue
        if c in "\"'":
            if c == "'" and i > 0 and text[i - 1].isalnum():  # a digit separator: 1'000'000
                out.append(" ")
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            out.append(" " * (min(j + 1, n) - i))
            i = j + 1
            continue
        out.append(c)
        i += 1
    return "".join(out)


def _is_function_head(head):
    """Whether the text before a '{' at namespace or class scope opens a function body."""
    h = head.strip()
    if not h or "(" not in h:
        return False
    if re.match(r'extern\s*$', h) or h.startswith("extern"):
        return False
    depth = 0
    for ch in h:  # '=' outside parentheses: an initialiser (`T x = f(y) {`...) or a default member
        if ch in "([":
            depth += 1
        elif ch in ")]":
            depth -= 1
        elif ch == "=" and depth == 0:
            return False
    words = set(_WORD.findall(re.sub(r"\([^()]*\)", " ", h)))  # the words outside the innermost parentheses
    first = _WORD.match(re.sub(r"^template\s*<[^{;]*?>\s*", "", h))
    return not (first and first.group(0) in _SCOPE_WORDS) and not (words & {"namespace"})


_QUALIFIERS = {"const", "noexcept", "override", "final", "mutable", "volatile", "try"}


def _brace_kind(head):
    """What a '{' at namespace or class scope opens, from the text before it: "function",
    "init" (a brace initialiser inside a constructor's initialiser list: the head goes on),
    "scope" (namespace, class, struct, union, enum, extern "C") or "other" (data)."""
    h = head.rstrip()
    words = _WORD.findall(h)
    last = words[-1] if words and re.search(r"\w$", h) else ""
    after_paren = h[h.rfind(")") + 1:] if ")" in h else ""
    if last and last not in _QUALIFIERS and "->" not in after_paren:
        # `name {`: a brace initialiser, or a scope's name
        if _is_function_head(h) and re.search(r"\)\s*(?:\w+\s*)*:(?!:)", h):  # `f(...) : a(b), c{`
            return "init"
        if re.search(r"\b(namespace|class|struct|union|enum)\b|^extern\b", h.strip()) or "=" not in h:
            return "scope"
        return "other"
    if _is_function_head(h):
        return "function"
    if "=" in h or not h.strip():
        return "other" if h.strip() else "scope"
    return "scope"


def functions(text):
    """(first line, name, length in lines) of every function body in C++ source `text`."""
    s = blank(text)
    out = []
    # The open braces: each (kind, head start offset, name); "scope" braces hold heads.
    stack = []
    head_start = 0
    for i, c in enumerate(s):
        at_scope = all(kind == "scope" for kind, _, _ in stack)
        if c == ";" and at_scope:
            head_start = i + 1
        elif c == "{":
            if not at_scope:
                stack.append(("other", i, ""))
                continue
            head = s[head_start:i]
            kind = _brace_kind(head)
            if kind == "function":
                names = _WORD.findall(head[: head.find("(")])
                stack.append((kind, head_start + len(head) - len(head.lstrip()), names[-1] if names else "?"))
            else:
                stack.append((kind, i, ""))
            if kind != "init":
                head_start = i + 1
        elif c == "}" and stack:
            kind, start, name = stack.pop()
            if kind == "function":
                first = s.count("\n", 0, start) + 1
                out.append((first, name, s.count("\n", 0, i) + 1 - first + 1))
            if kind != "init" and all(k == "scope" for k, _, _ in stack):
                head_start = i + 1
    return out
