"""Size check (decision 0045): no function in src/**/*.cc longer than MAX_FUNCTION_LINES
lines and no such file longer than MAX_FILE_LINES lines, so that a function reads as one step
and a file as one topic. Function bodies are found by a brace-matching heuristic: comments,
string and character literals are blanked, and a brace block whose opening is preceded by a
parameter list ')' (with const, noexcept, override or a trailing return type between) and not
by a control statement (if, for, while, switch, catch) is a function; only the outermost such
block counts, so lambdas and local classes belong to their function. Its length is the number
of lines from the opening brace to the closing one.

    python3 tests/architecture/check_sizes.py SOURCE_DIR [--also apps]
Prints one line per offender that is not allowed below and exits 1 if there is one; --also
adds more folders to measure (e.g. apps, to report offenders there).
"""
import pathlib
import re
import sys

MAX_FUNCTION_LINES = 120
MAX_FILE_LINES = 1000

# Exceptions, each with its reason (docs/decisions/0045-modal-types-in-estimation-and-size-limits.md).
# Keys: "path" for a file's length, "path:function" for a function's.
ALLOWED = {}

CONTROL = re.compile(r"\b(if|for|while|switch|catch)\s*\(")
SIGNATURE_END = re.compile(r"\)\s*(?:const\s*|noexcept\s*|override\s*|final\s*|->[^{};]*)*$")


def blank_comments_and_literals(text):
    """The text with comments and literals replaced by blanks, newlines kept."""
    out = []
    i, n = 0, len(text)
    while i < n:
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
            continue
        if text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("\n" * text.count("\n", i, j))
            i = j
            continue
        raw = re.match(r'R"([^(\s]*)\(', text[i:i + 20]) if text[i] == "R" else None
        if raw and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            end = text.find(")" + raw.group(1) + '"', i)
            j = n if end < 0 else end + len(raw.group(1)) + 2
            out.append('""' + "\n" * text.count("\n", i, j))
            i = j
            continue
        c = text[i]
        if c == "'" and i > 0 and text[i - 1].isalnum() and text[i - 1] not in "uUL":
            out.append(c)  # a digit separator (1'000), not a character literal
            i += 1
            continue
        if c in "\"'":
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            out.append(c + c)
            i = j + 1
            continue
        out.append(c)
        i += 1
    return "".join(out)


def is_function_head(head):
    flat = " ".join(head.split())
    if not SIGNATURE_END.search(flat) or CONTROL.search(flat):
        return False
    before_paren = flat.split("(", 1)[0]
    return "=" not in before_paren and "[" not in before_paren  # not a lambda or initialiser


def long_functions(text):
    """[(first line, name, lines)] of the outermost function bodies."""
    code = blank_comments_and_literals(text)
    found = []
    stack = []  # (offset of '{', is a function)
    for m in re.finditer(r"[{}]", code):
        if m.group() == "{":
            start = m.start()
            cut = max(code.rfind(";", 0, start), code.rfind("{", 0, start),
                      code.rfind("}", 0, start))
            head = code[cut + 1:start]
            inside_function = any(f for _, f in stack)
            stack.append((start, not inside_function and is_function_head(head)))
            if stack[-1][1]:
                names = re.findall(r"([~\w:]+)\s*\(", " ".join(head.split()))
                stack[-1] = (start, names[0] if names else "?")
        elif stack:
            start, function = stack.pop()
            if function:
                lines = code.count("\n", start, m.start()) + 1
                found.append((code.count("\n", 0, start) + 1, function, lines))
    return found


def main(args):
    root = pathlib.Path(args[0] if args and not args[0].startswith("--") else ".")
    folders = ["src"]
    if "--also" in args:
        folders += args[args.index("--also") + 1].split(",")
    problems = []
    for folder in folders:
        for path in sorted((root / folder).rglob("*.cc")):
            rel = path.relative_to(root).as_posix()
            text = path.read_text(encoding="utf-8")
            lines = text.count("\n")
            if lines > MAX_FILE_LINES and rel not in ALLOWED:
                problems.append(f"{rel}: {lines} lines (at most {MAX_FILE_LINES} per file)")
            for line, name, length in long_functions(text):
                short = name.split("::")[-1]
                if length > MAX_FUNCTION_LINES and f"{rel}:{short}" not in ALLOWED:
                    problems.append(f"{rel}:{line}: function {name} is {length} lines (at most "
                                    f"{MAX_FUNCTION_LINES})")
    for problem in problems:
        print(problem)
    print(f"check_sizes: {len(problems)} problem(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
