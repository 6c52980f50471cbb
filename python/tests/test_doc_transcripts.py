"""Every shell transcript in README.md and docs/ (blocks starting with ``$ ctid``; the rules are
in transcripts.py) is what this build prints: each file's transcripts run in order in one
scratch folder that sees the repository's examples/ and data/. A transcript whose commands read
a file no earlier command made and the repository does not hold shows the shape of an output
(placeholders such as <F>); it is named here and checked by the test the text points to."""

import glob
import os

import pytest

import transcripts

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUILD = os.environ.get("CTID_BUILD_DIR", os.path.join(ROOT, "build"))
CTID = os.path.join(BUILD, "apps", "ctid", "ctid")

# (file, first command) of shape-only transcripts, and the test that checks each shape.
SHAPES = {
    ("docs/cli-estimation.md", "ctid fit d.csv --poles 7 --zeros 6 -o r.json"):
        "tests/cli/fit_test.cc",
}


def documents():
    files = ["README.md"] + sorted(glob.glob("docs/**/*.md", root_dir=ROOT, recursive=True))
    return [f for f in files
            if transcripts.transcript_blocks(open(os.path.join(ROOT, f)).read())]


def test_the_documents_have_transcripts():
    assert "README.md" in documents()
    assert "docs/cli-estimation.md" in documents()


@pytest.mark.skipif(not os.path.exists(CTID), reason="ctid executable not built")
@pytest.mark.parametrize("document", documents())
def test_transcripts_are_what_this_build_prints(document, tmp_path):
    transcripts.link_repository_folders(ROOT, tmp_path)
    with open(os.path.join(ROOT, document)) as f:
        blocks = transcripts.transcript_blocks(f.read())
    for number, block in enumerate(blocks, 1):
        first = transcripts.steps(block)[0][0].split("#")[0].strip()
        if (document, first) in SHAPES:
            continue
        transcripts.run_transcript(block, CTID, tmp_path, f"{document}, transcript {number}")


def test_shape_only_transcripts_exist_and_name_a_test():
    for (document, first), test in SHAPES.items():
        with open(os.path.join(ROOT, document)) as f:
            firsts = [transcripts.steps(b)[0][0].split("#")[0].strip()
                      for b in transcripts.transcript_blocks(f.read())]
        assert first in firsts, f"{document} no longer shows `{first}`; update SHAPES"
        assert os.path.exists(os.path.join(ROOT, test)), test
