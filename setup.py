"""The compiled half of `pip install .` (decision 0047, pyproject.toml holds the rest).

setuptools copies python/ctid/*.py; this file adds the extension module _ctid, which CMake
builds (python/CMakeLists.txt, target _ctid) in

- $CTID_BUILD_DIR, when set (an existing, configured build tree, e.g. build/);
- otherwise build/, when it is a configured CMake tree (scripts/setup.sh makes it);
- otherwise build-pip/, configured here (Release, Python module only) on the first install.

Only the target _ctid is built, so an up-to-date tree costs a no-op `cmake --build`. The
module must have been built for the installing interpreter's ABI; a mismatch is one clear
error, not a package that fails on import.
"""

import glob
import os
import shutil
import subprocess
import sys
import sysconfig

from setuptools import Distribution, setup
from setuptools.command.build_py import build_py

ROOT = os.path.dirname(os.path.abspath(__file__))


def _build_dir():
    given = os.environ.get("CTID_BUILD_DIR")
    if given:
        if not os.path.isfile(os.path.join(given, "CMakeCache.txt")):
            sys.exit(f"CTID_BUILD_DIR={given}: not a configured CMake build tree")
        return os.path.abspath(given)
    default = os.path.join(ROOT, "build")
    if os.path.isfile(os.path.join(default, "CMakeCache.txt")):
        return default
    own = os.path.join(ROOT, "build-pip")
    if not os.path.isfile(os.path.join(own, "CMakeCache.txt")):
        generator = ["-G", "Ninja"] if shutil.which("ninja") else []
        subprocess.run(["cmake", "-S", ROOT, "-B", own, *generator,
                        "-DCMAKE_BUILD_TYPE=Release", "-DCTID_BUILD_TESTS=OFF",
                        "-DCTID_BUILD_APPS=OFF", "-DCTID_BUILD_BENCHMARKS=OFF",
                        "-DCTID_BUILD_PYTHON=ON", f"-DPython3_EXECUTABLE={sys.executable}"],
                       check=True)
    return own


def _compiled_module():
    """Builds the target _ctid and returns the path of the module file."""
    build = _build_dir()
    jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", "2")
    subprocess.run(["cmake", "--build", build, "-j", jobs, "--target", "_ctid"], check=True)
    suffix = sysconfig.get_config_var("EXT_SUFFIX")
    found = glob.glob(os.path.join(build, "python", "ctid", "_ctid*.so"))
    wanted = [path for path in found if path.endswith(suffix)]
    if not wanted:
        sys.exit(f"{build}/python/ctid: no _ctid{suffix} for {sys.executable} (found: "
                 f"{', '.join(os.path.basename(p) for p in found) or 'none'}); build with "
                 "-DPython3_EXECUTABLE set to this interpreter")
    return wanted[0]


class BuildWithModule(build_py):
    """build_py that also places the compiled module in the package."""

    def run(self):
        super().run()
        module = _compiled_module()
        target = os.path.join(self.build_lib, "ctid", os.path.basename(module))
        self.mkpath(os.path.dirname(target))
        self.copy_file(module, target)


class BinaryDistribution(Distribution):
    """A wheel for this platform and Python (the module is compiled), not a pure one."""

    def has_ext_modules(self):
        return True


setup(cmdclass={"build_py": BuildWithModule}, distclass=BinaryDistribution,
      options={"build": {"build_base": "build-setuptools"}})
