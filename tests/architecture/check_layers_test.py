"""check_layers.py fails on a broken front door (decisions 0044, 0069): a copy of the tree
passes, and each offending include, or a package module's call of an estimator binding, added to
it makes the script exit 1 with one line naming it.

    python3 tests/architecture/check_layers_test.py SOURCE_DIR
"""
import pathlib
import shutil
import subprocess
import sys
import tempfile
import unittest

SCRIPT = pathlib.Path(__file__).resolve().parent / "check_layers.py"
ROOT = pathlib.Path(".")


class CheckLayersTest(unittest.TestCase):
    def setUp(self):
        self.temp = tempfile.TemporaryDirectory()
        self.tree = pathlib.Path(self.temp.name)
        shutil.copy(ROOT / "CMakeLists.txt", self.tree / "CMakeLists.txt")
        for folder in ("include", "src", "tests", "apps", "python/src", "python/ctid"):
            shutil.copytree(ROOT / folder, self.tree / folder,
                            ignore=shutil.ignore_patterns("*.csv", "*.json", "*.npy", "*.txt"))

    def tearDown(self):
        self.temp.cleanup()

    def run_check(self):
        done = subprocess.run([sys.executable, str(SCRIPT), str(self.tree)],
                              capture_output=True, text=True, check=False)
        lines = done.stdout.splitlines()
        self.assertTrue(lines and lines[-1].startswith("check_layers: "), done.stdout)
        return done.returncode, lines[:-1]

    def add_include(self, relative, header):
        """Appends #include "header" to a file of the copy; returns its line number."""
        path = self.tree / relative
        text = path.read_text(encoding="utf-8")
        path.write_text(text + f'#include "{header}"\n', encoding="utf-8")
        return text.count("\n") + 1

    def test_the_tree_passes(self):
        self.assertEqual(self.run_check(), (0, []))

    def test_a_command_including_an_estimator_header_fails(self):
        line = self.add_include("apps/ctid/oma_command.cc", "ctid/oma/oma.h")
        code, problems = self.run_check()
        self.assertEqual(code, 1)
        self.assertEqual(len(problems), 1, problems)
        self.assertTrue(problems[0].startswith(f"apps/ctid/oma_command.cc:{line}: "), problems)
        self.assertIn("'ctid/oma/oma.h'", problems[0])
        self.assertIn("estimator module 'oma'", problems[0])

    def test_an_app_header_including_an_estimator_header_fails(self):
        line = self.add_include("apps/ctid/data_flags.h", "ctid/refined_iv/irregular_srivc.h")
        code, problems = self.run_check()
        self.assertEqual(code, 1)
        self.assertEqual(len(problems), 1, problems)
        self.assertTrue(problems[0].startswith(f"apps/ctid/data_flags.h:{line}: "), problems)
        self.assertIn("'refined_iv'", problems[0])

    def test_a_binding_fails_unless_it_is_listed(self):
        line = self.add_include("python/src/bind_frf_fit.cc", "ctid/frf_fit/frf_matrix_fit.h")
        # The listed bindings of the papers' estimators may include estimator headers.
        self.add_include("python/src/bind_refined_iv.cc", "ctid/refined_iv/srivc.h")
        self.add_include("python/src/bind_delayed_feedback.cc", "ctid/delayed_feedback/regressors.h")
        code, problems = self.run_check()
        self.assertEqual(code, 1)
        self.assertEqual(len(problems), 1, problems)
        self.assertTrue(problems[0].startswith(f"python/src/bind_frf_fit.cc:{line}: "), problems)
        self.assertIn("estimator module 'frf_fit'", problems[0])

    def test_a_package_module_calling_an_estimator_binding_fails(self):
        path = self.tree / "python/ctid/report.py"
        text = path.read_text(encoding="utf-8")
        path.write_text(text + '\n\ndef _quick(data, order):\n'
                        '    """Not ctid.srivc(data) in a docstring."""  # nor _ctid.lssvf here\n'
                        '    from ._ctid import (\n        AdditiveModel, additive_srivc)\n'
                        '    return _ctid.srivc(data, order)\n', encoding="utf-8")
        first = text.count("\n") + 6  # the line naming additive_srivc
        code, problems = self.run_check()
        self.assertEqual(code, 1)
        self.assertEqual(problems, [
            f"python/ctid/report.py:{first}: uses 'additive_srivc', an estimator bound by "
            "python/src/bind_refined_iv.cc; the package reaches estimators through "
            "'identification' (decision 0069)",
            f"python/ctid/report.py:{first + 1}: uses 'srivc', an estimator bound by "
            "python/src/bind_refined_iv.cc; the package reaches estimators through "
            "'identification' (decision 0069)"])

    def test_an_estimator_module_including_identification_fails(self):
        line = self.add_include("src/oma/oma.cc", "ctid/identification/identification.h")
        code, problems = self.run_check()
        self.assertEqual(code, 1)
        self.assertEqual(len(problems), 1, problems)
        self.assertTrue(problems[0].startswith(f"src/oma/oma.cc:{line}: "), problems)
        self.assertIn("estimator module 'oma' includes 'identification'", problems[0])

    def test_an_estimator_module_depending_on_identification_fails(self):
        cmake = self.tree / "CMakeLists.txt"
        text = cmake.read_text(encoding="utf-8")
        declared = "ctid_add_layer(process_model DEPENDS ctid_refined_iv"
        self.assertIn(declared, text)
        cmake.write_text(text.replace(declared, declared + " ctid_identification"),
                         encoding="utf-8")
        line = self.add_include("src/process_model/process_model.cc",
                                "ctid/identification/two_stage.h")
        code, problems = self.run_check()
        self.assertEqual(code, 1)
        self.assertIn("CMakeLists.txt: estimator module 'process_model' depends on "
                      "'identification', the front door above it (decision 0044)", problems)
        self.assertIn(f"src/process_model/process_model.cc:{line}: estimator module "
                      "'process_model' includes 'identification', the front door above it "
                      "(decision 0044)", problems)


if __name__ == "__main__":
    ROOT = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".").resolve()
    unittest.main(argv=sys.argv[:1])
