"""Catch check (decision 0045, section 2; decision 0069): in every estimator module, in
src/identification and in src/study a numerical outcome is a value the code steers on, never an InvalidArgument caught from a deep
call. Every `catch` left there is listed below with its reason, by file and enclosing function
(found as check_sizes.py finds functions); a catch anywhere else in those layers, or a listed
one that is gone, is reported.

    python3 tests/architecture/check_catches.py SOURCE_DIR
Prints one line per problem and exits 1 if there is one.
"""
import pathlib
import re
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from check_sizes import blank_comments_and_literals, long_functions  # noqa: E402

# Every estimator module, the front door above them and the paper studies.
FOLDERS = ("src/refined_iv", "src/identification", "src/oma", "src/process_model", "src/frf_fit",
           "src/delayed_feedback", "src/output_error", "src/study")

# "path:function": (number of catches, reason).
ALLOWED = {
    "src/refined_iv/input_delay_scan.cc:scan_input_delay":
        (1, "the estimator passed in refuses a delay by throwing; the scan records it and "
            "rethrows the first message with its context when every delay is refused"),
    "src/refined_iv/initialization.cc:refined_candidate":
        (1, "a candidate's refinement is a whole SRIVC or CLSRIVC run on the screening piece, "
            "and the engine refuses a piece with too few samples or too little excitation for "
            "the order by throwing, as it refuses a caller's record, and a degenerate start "
            "given as the initial model is refused the same way"),
    "src/refined_iv/unstable_clsrivc.cc:explained_input_start":
        (1, "the first stage is a whole SRIVC run of r -> u, which the engine refuses by "
            "throwing when r excites too little for the loop's order, and a start screen of "
            "its own"),
    "src/refined_iv/clsrivc_continuous.cc:indirect_start":
        (1, "the first stage is a whole SRIVC run of r -> y of the loop's order, which the "
            "engine refuses by throwing when r excites too little for it; the other starts "
            "remain"),
    "src/identification/identification.cc:identify_records":
        (1, "the stabilised-prefilter fallback after an unusable closed-loop fit: its bad-input "
            "refusals are ruled out first as a value (unstable_clsrivc_refusal); what is left is "
            "a record that forms no start of the order, which initial_transfer_function refuses "
            "by throwing as the engine does, and then the engine's fit stands"),
    "src/identification/mode_tracking.cc:track_modes":
        (1, "a window the estimator refuses as bad input (too short, too little excitation) is "
            "recorded as a refused window with the message, and the other windows go on"),
    "src/identification/mode_tracking.cc:track_mimo_modes":
        (1, "a window the shared-pole estimator refuses as bad input is a refused window"),
    "src/identification/mode_tracking.cc:track_output_only_modes":
        (1, "a window oma() refuses as bad input (a constant channel, too few samples for the "
            "orders) is a refused window"),
    "src/identification/structure_scan.cc:fit_candidate":
        (1, "a candidate structure the estimator refuses for this record (too many parameters "
            "for its samples) is an unusable candidate with the message; the others are scored"),
    "src/identification/mimo_structure_scan.cc:fit_count":
        (1, "a mode count the shared-pole estimator refuses for this record is an unusable "
            "count with the message"),
    "src/process_model/process_model.cc:output":
        (2, "a solver's trial point or a difference step whose parameters form no finite model "
            "(overflowing coefficients, a state matrix without eigenvalues), which the core types "
            "refuse by throwing; output() returns it as an empty output, an infeasible point"),
    "src/process_model/process_model.cc:srivc_process_start":
        (2, "one candidate start is a whole SRIVC run at one delay, which the engine refuses by "
            "throwing when the record cannot support the orders there; the default start stands"),
    "src/study/paper_study.cc:run_study_case":
        (1, "not a steer: an estimator that refuses a run's record is recorded as the run's "
            "error with the message, so that the run can be replayed alone; the study goes on"),
    "src/oma/multi_setup.cc:oma_multi_setup":
        (1, "not a steer: a setup's refusal is rethrown with the setup's number"),
}


def catches(text):
    """{function: count} of the catch clauses in text, by enclosing outermost function."""
    code = blank_comments_and_literals(text)
    spans = long_functions(text)
    found = {}
    for m in re.finditer(r"\bcatch\s*\(", code):
        line = code.count("\n", 0, m.start()) + 1
        owner = "?"
        for first, name, length in spans:
            if first <= line < first + length:
                owner = name.split("::")[-1]
        found[owner] = found.get(owner, 0) + 1
    return found


def main(args):
    root = pathlib.Path(args[0] if args else ".")
    problems = []
    seen = set()
    for path in sorted(p for folder in FOLDERS for p in (root / folder).rglob("*.cc")):
        rel = path.relative_to(root).as_posix()
        for function, count in catches(path.read_text(encoding="utf-8")).items():
            key = f"{rel}:{function}"
            seen.add(key)
            allowed = ALLOWED.get(key, (0, ""))[0]
            if count != allowed:
                problems.append(f"{key}: {count} catch clause(s), {allowed} allowed (steer on a "
                                "returned value instead, decision 0045)")
    for key in sorted(set(ALLOWED) - seen):
        problems.append(f"{key}: listed but has no catch any more; remove it from ALLOWED")
    for problem in problems:
        print(problem)
    print(f"check_catches: {len(problems)} problem(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
