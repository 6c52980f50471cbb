"""Every options class of the C++ headers reaches Python and JSON with the same fields and
defaults.

The classes are found by reading include/ctid/**/*.h (every `struct <Name>Options` with a
body), not from a list kept here, and each one's data members are read from its struct body:
a member added in C++ without being listed in its fields() fails here. For every class:
ctid.<Name> exists; its `fields` are the struct's data members; each Python default equals
the value ctid.options_to_json writes; the defaults round-trip through options_from_json;
an unknown keyword raises TypeError; and a value breaking a field's numeric rule makes
validate() raise a ValueError that names <Name>.<field>.
"""

import json
import math
import pathlib
import re

import pytest

import ctid

ROOT = pathlib.Path(__file__).resolve().parents[2]
HEADERS = sorted((ROOT / "include" / "ctid").rglob("*.h"))

# ---- Reading the C++ headers --------------------------------------------------------------

_TOKENS = re.compile(r'"(?:\\.|[^"\\])*"|\'(?:\\.|[^\'\\])*\'|//[^\n]*|/\*.*?\*/', re.S)


def _code(text):
    """The text without comments, every string and character literal emptied."""

    def replace(match):
        token = match.group(0)
        if token.startswith('"'):
            return '""'
        if token.startswith("'"):
            return "' '"
        return " "

    return _TOKENS.sub(replace, text)


_STRUCT = re.compile(r"\bstruct\s+(\w+)\s*(?:final\s*)?(?::\s*(?:public\s+)?([\w:]+)\s*)?\{")


def _struct_bodies():
    """{name: (base or None, body text)} for every struct defined in the headers."""
    found = {}
    for header in HEADERS:
        code = _code(header.read_text())
        for match in _STRUCT.finditer(code):
            depth, i = 1, match.end()
            while depth > 0:
                depth += {"{": 1, "}": -1}.get(code[i], 0)
                i += 1
            base = match.group(2).split("::")[-1] if match.group(2) else None
            found[match.group(1)] = (base, code[match.end() : i - 1])
    return found


_SKIP = ("static ", "using ", "typedef ", "friend ", "enum ", "struct ", "class ", "template")


def _declared_members(body):
    """Names of the non-static data members declared at the top level of a struct body."""
    statements, current, depth, head = [], "", 0, ""
    for c in body:
        if c == "{":
            if depth == 0:
                head = current
            depth += 1
            current += c
        elif c == "}":
            depth -= 1
            current += c
            if depth == 0 and "(" in head:  # the end of a member function's body
                current = ""
        elif c == ";" and depth == 0:
            statements.append(current)
            current = ""
        else:
            current += c
    names = []
    for statement in statements:
        statement = re.sub(r"^\s*(public|private|protected)\s*:", "", statement).strip()
        if not statement or statement.startswith(_SKIP):
            continue
        declarator = re.split(r"[={]", statement, maxsplit=1)[0]
        if "(" in declarator:  # a member function
            continue
        names.append(re.findall(r"\w+", declarator)[-1])
    return names


STRUCTS = _struct_bodies()


def _members(name):
    base, body = STRUCTS[name]
    inherited = _members(base) if base in STRUCTS else []
    return inherited + _declared_members(body)


OPTIONS = sorted(name for name in STRUCTS if re.fullmatch(r"\w+Options", name))
assert len(OPTIONS) >= 10, f"too few options structs found in the headers: {OPTIONS}"


CASES = [pytest.param(name, id=name) for name in OPTIONS]

# ---- Values -------------------------------------------------------------------------------


def _as_json(value):
    """A Python field value as options_to_json writes it."""
    if value is None or isinstance(value, (bool, int, str)):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, (list, tuple)):
        return [_as_json(each) for each in value]
    if hasattr(type(value), "fields"):
        return {f: _as_json(getattr(value, f)) for f in type(value).fields}
    if hasattr(value, "name") and hasattr(type(value), "__members__"):
        return value.name
    raise AssertionError(f"no JSON form known for {value!r}")


_RULE = re.compile(
    r"^(?:finite and )?(?:(?P<op>>=|>|<=) (?P<bound>\S+)"
    r"|in (?P<lo_b>[\[(])(?P<lo>[^,]+), (?P<hi>[^\])]+)(?P<hi_b>[\])]))$"
)


def _rule(text):
    match = _RULE.match(text)
    return match.groupdict() if match else None


def _typed(example, x):
    return int(x) if isinstance(example, int) and not isinstance(example, bool) else float(x)


def _breaking(rule, example):
    """A value that breaks the rule (of the type of `example`)."""
    if rule["op"] == ">=":
        return _typed(example, float(rule["bound"]) - 1)
    if rule["op"] == ">":
        return _typed(example, float(rule["bound"]))
    if rule["op"] == "<=":
        return _typed(example, float(rule["bound"]) + 1)
    low = float(rule["lo"])
    return _typed(example, low - 1 if rule["lo_b"] == "[" else low)


def _following(rule, example):
    """A value that follows the rule (of the type of `example`)."""
    if rule["op"] in (">=", "<="):
        return _typed(example, float(rule["bound"]))
    if rule["op"] == ">":
        return _typed(example, float(rule["bound"]) + 1)
    low, high = float(rule["lo"]), float(rule["hi"])
    if isinstance(example, int):
        return int(low) if rule["lo_b"] == "[" else int(low) + 1
    return (low + high) / 2


def _element_example(cls, field):
    """An element of a vector field's default; for an empty one an int, which Python accepts
    for a list of numbers of either kind."""
    default = getattr(cls(), field)
    return default[0] if default else 0


def _valid_instance(name):
    """The defaults, with any field whose default breaks its own rule (a required field such
    as PeriodicFrfOptions.period_length) set to a value that follows the rule."""
    cls = getattr(ctid, name)
    options = cls()
    for _ in range(len(cls.fields) + 1):
        try:
            options.validate()
            return options
        except ValueError as error:
            match = re.match(rf"{name}\.(\w+)", str(error))
            field = match.group(1) if match else None
            rule = _rule(cls.field_rules.get(field, "")) if field else None
            if rule is None or isinstance(getattr(options, field), list):
                pytest.skip(f"no valid {name} from its rules: {error}")
            setattr(options, field, _following(rule, getattr(options, field)))
    pytest.skip(f"no valid {name} from its rules")


# ---- Tests --------------------------------------------------------------------------------


@pytest.mark.parametrize("name", CASES)
def test_options_class_is_bound(name):
    assert hasattr(ctid, name), f"ctid.{name} is not bound"
    assert name in ctid.options_classes(), f"{name} is not reachable from JSON"


@pytest.mark.parametrize("name", CASES)
def test_fields_are_the_struct_members(name):
    cls = getattr(ctid, name)
    declared = _members(name)
    listed = list(cls.fields)
    assert len(set(listed)) == len(listed), f"{name}.fields repeats a name: {listed}"
    assert sorted(listed) == sorted(declared), (
        f"{name}: members declared in C++ {declared} but fields() lists {listed}"
    )
    assert set(cls.field_docs) == set(listed)
    assert all(cls.field_docs[f] for f in listed), f"{name}: a field has no doc"


@pytest.mark.parametrize("name", CASES)
def test_python_defaults_are_the_json_defaults(name):
    cls = getattr(ctid, name)
    document = ctid.options_to_json(cls())
    assert sorted(document) == sorted(cls.fields)
    defaults = cls()
    for field in cls.fields:
        assert _as_json(getattr(defaults, field)) == document[field], f"{name}.{field}"


@pytest.mark.parametrize("name", CASES)
def test_defaults_round_trip_through_json(name):
    cls = getattr(ctid, name)
    document = ctid.options_to_json(_valid_instance(name))
    from_dict = ctid.options_from_json(cls, document)
    assert isinstance(from_dict, cls)
    assert from_dict == _valid_instance(name)
    assert ctid.options_from_json(name, json.dumps(document)) == from_dict
    assert ctid.options_to_json(from_dict) == document


@pytest.mark.parametrize("name", CASES)
def test_unknown_keyword_is_a_type_error(name):
    cls = getattr(ctid, name)
    with pytest.raises(TypeError, match="not_a_field"):
        cls(not_a_field=1)


@pytest.mark.parametrize("name", CASES)
def test_unknown_json_key_is_a_value_error(name):
    with pytest.raises(ValueError, match=f"unknown field 'not_a_field'; the fields of {name}"):
        ctid.options_from_json(name, {"not_a_field": 1})


@pytest.mark.parametrize("name", CASES)
def test_a_value_breaking_a_rule_names_the_field(name):
    cls = getattr(ctid, name)
    ruled = {f: _rule(text) for f, text in cls.field_rules.items() if _rule(text)}
    if not ruled:
        pytest.skip(f"{name} has no field with a numeric rule")
    for field, rule in ruled.items():
        options = _valid_instance(name)
        default = getattr(options, field)
        if isinstance(default, list):
            bad = [_breaking(rule, _element_example(cls, field))]
        else:
            bad = _breaking(rule, default)
        try:
            setattr(options, field, bad)
        except TypeError:  # an optional integer field whose default is None
            setattr(options, field, int(bad))
        with pytest.raises(ValueError, match=rf"^{name}\.{field}\b") as info:
            options.validate()
        assert "it must be" in str(info.value)


def test_the_scan_sees_the_options_of_every_layer():
    # Guards the header scan itself: it finds the pilot and members with initialisers.
    assert "RefinedIvOptions" in OPTIONS and "StudyOptions" in OPTIONS
    assert "damping_ratios" in _members("ModeRelocationOptions")
    assert "validate" not in _members("RefinedIvOptions")


def test_nested_values_keep_their_json_form():
    options = ctid.ModeRelocationOptions(
        damping_ratios=[0.5], criterion=ctid.RelocationCriterion.output_error
    )
    document = ctid.options_to_json(options)
    assert document["damping_ratios"] == [0.5]
    assert document["criterion"] == "output_error"
    assert ctid.options_from_json("ModeRelocationOptions", document) == options
    with pytest.raises(ValueError, match=r"ModeRelocationOptions\.criterion: 'best' is not one"):
        ctid.options_from_json(ctid.ModeRelocationOptions, {"criterion": "best"})
    with pytest.raises(ValueError, match="is not an options class"):
        ctid.options_from_json("Nothing", {})


# ---- Results and reports -------------------------------------------------------------------
# The same discovery for what the library returns: every `*Result` and `*Report` struct of
# the headers is a Python class whose `fields` are the C++ data members (its base's first),
# so no member of a result is out of Python's reach.
RESULTS = sorted(name for name in STRUCTS if re.fullmatch(r"\w+(Result|Report)", name))


def test_the_scan_sees_the_results_of_both_modules():
    assert {"EstimationResult", "FeedbackIdentificationResult", "ValidationReport"} <= set(RESULTS)


@pytest.mark.parametrize("name", RESULTS)
def test_result_fields_are_the_struct_members(name):
    assert hasattr(ctid, name), f"ctid.{name} is not bound"
    cls = getattr(ctid, name)
    assert hasattr(cls, "fields"), f"ctid.{name} is not bound from a field list"
    assert list(cls.fields) == _members(name), name
    for field in cls.fields:
        assert hasattr(cls, field), f"ctid.{name}.{field}"
