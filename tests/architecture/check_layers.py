"""Layering check: every #include "ctid/<layer>/..." in a layer's headers, sources and tests
names that layer or one it depends on, as declared by ctid_add_layer(<layer> DEPENDS ...) in
the top-level CMakeLists.txt (so the CMake dependencies and the includes cannot drift apart),
and each declared ctid dependency is used by at least one include. The two paper modules
(refined_iv, delayed_feedback) never reach each other.

One front door (issue 32, decision 0044): no file under apps/ includes a header of an estimator
module (ESTIMATOR_MODULES); nor does one under python/src, except the bindings listed in
PYTHON_ESTIMATOR_BINDINGS, which expose the papers' estimators themselves on purpose. Both
reach estimators, their options and their results through the identification layer. No
estimator module includes anything from identification. The package's own modules
(python/ctid/**/*.py) call none of the functions those listed bindings define (decision 0069):
they are there for a user to call by name, and the package's workflows use the front door.

    python3 tests/architecture/check_layers.py SOURCE_DIR
Exit 0 when the tree is layered; otherwise one line per offending include, exit 1.
"""
import io
import pathlib
import re
import sys
import tokenize

PAPER_MODULES = ("refined_iv", "delayed_feedback")
# Modules that hold estimators and nothing that chooses between them; the identification
# layer above them is the front door.
ESTIMATOR_MODULES = ("refined_iv", "delayed_feedback", "frf_fit", "oma", "process_model",
                     "output_error")
FRONT_DOOR = "identification"
# python/src files that may include estimator headers, each with the reason (decision 0044).
PYTHON_ESTIMATOR_BINDINGS = {
    "bind_refined_iv.cc": "binds paper 000's estimators themselves (srivc, clsrivc, "
                          "additive_srivc, covariance, initialisation, delay scan, relocation, "
                          "recursive, irregular and shared-pole SRIVC) for their own study",
    "bind_delayed_feedback.cc": "binds paper 002's steps themselves (step-1 least squares and "
                                "structured IV, separation, output-error refinement, Cramer-Rao "
                                "bound, delay scan) for their own study",
}


def declared_layers(cmake_text):
    """{layer: set of direct ctid layer dependencies}, in declaration order."""
    layers = {}
    for name, deps in re.findall(r"ctid_add_layer\((\w+)\s+DEPENDS([^)]*)\)", cmake_text):
        layers[name] = {d[len("ctid_"):] for d in deps.split() if d.startswith("ctid_")}
    return layers


def closure(layers, name):
    seen, stack = set(), [name]
    while stack:
        for dep in layers[stack.pop()]:
            if dep not in seen:
                seen.add(dep)
                stack.append(dep)
    return seen


def included_layers(path):
    text = path.read_text(encoding="utf-8")
    return [(m.group(1), text.count("\n", 0, m.start()) + 1)
            for m in re.finditer(r'#include\s+"(?:ctid/)?(\w+)/', text)]


def ctid_includes(path):
    """[(module, header, line)] of every #include "ctid/<module>/<header>" (or <...>)."""
    text = path.read_text(encoding="utf-8")
    return [(m.group(1), m.group(2), text.count("\n", 0, m.start()) + 1)
            for m in re.finditer(r'#include\s+["<]ctid/(\w+)/([^">]+)[">]', text)]


def source_files(folder):
    return [p for p in sorted(folder.rglob("*")) if p.suffix in (".h", ".cc")] \
        if folder.is_dir() else []


def front_door_problems(root):
    """apps/ and python/src reach no estimator module but through identification (less the
    listed bindings)."""
    problems = []
    for where, exempt in (("apps", {}), ("python/src", PYTHON_ESTIMATOR_BINDINGS)):
        for path in source_files(root / where):
            if path.name in exempt and path.parent == root / where:
                continue
            for module, header, line in ctid_includes(path):
                if module in ESTIMATOR_MODULES:
                    problems.append(
                        f"{path.relative_to(root)}:{line}: includes 'ctid/{module}/{header}', a "
                        f"header of the estimator module '{module}'; {where} reaches estimators "
                        f"through '{FRONT_DOOR}' (decision 0044)")
    return problems


def bound_estimators(root):
    """{function name: binding file} of every m.def("name", ...) in the listed bindings."""
    names = {}
    for binding in PYTHON_ESTIMATOR_BINDINGS:
        path = root / "python" / "src" / binding
        if path.is_file():
            for name in re.findall(r'\bm\.def\(\s*"(\w+)"', path.read_text(encoding="utf-8")):
                names[name] = binding
    return names


def code_references(text):
    """[(name, line)] of every module.name in the code of a Python file (strings and comments
    skipped), module being _ctid or ctid, and of every name imported from ._ctid."""
    tokens = [t for t in tokenize.generate_tokens(io.StringIO(text).readline)
              if t.type in (tokenize.NAME, tokenize.OP, tokenize.NEWLINE)]
    found = []
    for i, token in enumerate(tokens[:-2]):
        if token.string in ("_ctid", "ctid") and tokens[i + 1].string == "." \
                and tokens[i + 2].type == tokenize.NAME:
            found.append((tokens[i + 2].string, tokens[i + 2].start[0]))
        if token.string == "import" and i > 0 and tokens[i - 1].string == "_ctid":
            for later in tokens[i + 1:]:
                if later.type == tokenize.NAME:
                    found.append((later.string, later.start[0]))
                elif later.string not in (",", "(", ")"):
                    break
    return found


def python_package_problems(root):
    """python/ctid modules use no estimator that the listed bindings expose."""
    names = bound_estimators(root)
    package = root / "python" / "ctid"
    problems = []
    for path in sorted(package.rglob("*.py")) if package.is_dir() else []:
        for name, line in code_references(path.read_text(encoding="utf-8")):
            if name in names:
                problems.append(
                    f"{path.relative_to(root)}:{line}: uses '{name}', an estimator bound by "
                    f"python/src/{names[name]}; the package reaches estimators through "
                    f"'{FRONT_DOOR}' (decision 0069)")
    return problems


def main(root):
    root = pathlib.Path(root)
    layers = declared_layers((root / "CMakeLists.txt").read_text(encoding="utf-8"))
    problems = []
    for module in PAPER_MODULES:
        if module not in layers:
            problems.append(f"CMakeLists.txt: no ctid_add_layer({module} ...)")
    for module in ESTIMATOR_MODULES:
        if module in layers and FRONT_DOOR in closure(layers, module):
            problems.append(f"CMakeLists.txt: estimator module '{module}' depends on "
                            f"'{FRONT_DOOR}', the front door above it (decision 0044)")
    a, b = PAPER_MODULES
    if a in layers and b in layers and (a in closure(layers, b) or b in closure(layers, a)):
        problems.append(f"CMakeLists.txt: {a} and {b} must not depend on each other")
    for layer, direct in layers.items():
        allowed = closure(layers, layer) | {layer}
        used = set()
        folders = [root / "include" / "ctid" / layer, root / "src" / layer, root / "tests" / layer]
        for folder in folders:
            for path in sorted(folder.rglob("*")) if folder.is_dir() else []:
                if path.suffix not in (".h", ".cc"):
                    continue
                for included, line in included_layers(path):
                    if included not in layers:
                        continue  # e.g. "internal/..." or a test-support folder
                    used.add(included)
                    if layer in ESTIMATOR_MODULES and included == FRONT_DOOR:
                        problems.append(
                            f"{path.relative_to(root)}:{line}: estimator module '{layer}' "
                            f"includes '{FRONT_DOOR}', the front door above it (decision 0044)")
                    elif included not in allowed:
                        problems.append(
                            f"{path.relative_to(root)}:{line}: layer '{layer}' includes "
                            f"'{included}', which is not below it (allowed: "
                            f"{', '.join(sorted(allowed))})")
        for dep in sorted(direct - used):
            problems.append(f"CMakeLists.txt: layer '{layer}' declares a dependency on "
                            f"'{dep}' but includes nothing from it")
    problems += front_door_problems(root)
    problems += python_package_problems(root)
    for problem in problems:
        print(problem)
    print(f"check_layers: {len(layers)} layers, {len(problems)} problem(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else "."))
