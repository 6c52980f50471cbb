"""The map stays true (issue 32): docs/architecture.md names every ctid command (as
`ctid <name>` in its table of commands) and every layer declared in the top-level
CMakeLists.txt (in its layer diagram), and the umbrella header include/ctid/ctid.h includes
every public header.

    python3 tests/architecture/check_map.py SOURCE_DIR [CTID_TOOL]
Exit 0 when the map is complete; otherwise one line per omission, exit 1.
"""
import pathlib
import re
import subprocess
import sys


def commands(root, tool=None):
    """The subcommand names registered by apps/ctid/*_command.cc with a literal name, and, given
    the built tool, every name its --help lists (step and impulse are named by an enum)."""
    names = set()
    for path in sorted((root / "apps" / "ctid").glob("*_command.cc")):
        names.update(re.findall(r'add_subcommand\(\s*"([a-z][a-z-]*)"', path.read_text()))
    if tool:
        listing = subprocess.run([tool, "--help"], capture_output=True, text=True,
                                 check=True).stdout
        section = listing.split("Subcommands:", 1)[1]
        names.update(re.findall(r"^  ([a-z][a-z-]*)\s", section, flags=re.MULTILINE))
    return names


def layers(root):
    text = (root / "CMakeLists.txt").read_text()
    return re.findall(r"ctid_add_layer\((\w+)", text)


def layer_diagram(architecture):
    """The first fenced block after '## Layers'."""
    section = architecture.split("## Layers", 1)[1]
    return section.split("```", 2)[1]


def public_headers(root):
    include = root / "include"
    return sorted(str(p.relative_to(include)) for p in (include / "ctid").glob("*/*.h"))


def omissions(root, tool=None):
    architecture = (root / "docs" / "architecture.md").read_text()
    problems = []
    for name in sorted(commands(root, tool)):
        if f"`ctid {name}`" not in architecture:
            problems.append(f"docs/architecture.md does not name the command `ctid {name}`")
    diagram = layer_diagram(architecture)
    for name in layers(root):
        if not re.search(rf"\b{name}\b", diagram):
            problems.append(f"docs/architecture.md's layer diagram has no line for {name}")
    umbrella = (root / "include" / "ctid" / "ctid.h").read_text()
    included = set(re.findall(r'#include\s+"(ctid/[^"]+)"', umbrella))
    for header in public_headers(root):
        if header not in included:
            problems.append(f"include/ctid/ctid.h does not include {header}")
    return problems


def main(argv):
    root = pathlib.Path(argv[1] if len(argv) > 1 else ".").resolve()
    tool = argv[2] if len(argv) > 2 else None
    problems = omissions(root, tool)
    for problem in problems:
        print(problem)
    if not problems:
        print(f"map: {len(commands(root, tool))} commands, {len(layers(root))} layers, "
              f"{len(public_headers(root))} headers")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
