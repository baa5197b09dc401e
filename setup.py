"""Builds peelcd's Python module with CMake for pip (pyproject.toml; docs/python.md).

The extension is the CMake target _peelcd: configured in build/pip (Release, without the
command line and the tests) with this interpreter, or taken from the build tree that
$PEELCD_BUILD_DIR names, where it was built (ctest's pip test does that). The version is
CMakeLists.txt's project version.
"""
import os
import re
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = os.path.dirname(os.path.abspath(__file__))


def version():
    with open(os.path.join(ROOT, "CMakeLists.txt"), encoding="utf-8") as f:
        m = re.search(r"project\(peelcd VERSION ([0-9.]+)", f.read())
    if not m:
        raise RuntimeError("peelcd: no project(peelcd VERSION ...) in CMakeLists.txt")
    return m.group(1)


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build_dir = os.environ.get("PEELCD_BUILD_DIR")
        if build_dir:
            build_dir = os.path.abspath(build_dir)
        else:
            build_dir = os.path.join(ROOT, "build", "pip")
            # pip hides this output unless run with -v: say once what the wait is.
            sys.stderr.write("peelcd: building the C++ library and the module with CMake (minutes; "
                             "pip install -v . shows its progress)\n")
            subprocess.check_call(["cmake", "-S", ROOT, "-B", build_dir, "-DCMAKE_BUILD_TYPE=Release",
                                   "-DPEELCD_BUILD_APPS=OFF", "-DPEELCD_BUILD_TESTS=OFF", "-DPEELCD_PYTHON=ON",
                                   "-DPython3_EXECUTABLE=" + sys.executable])
            subprocess.check_call(["cmake", "--build", build_dir, "--target", "_peelcd", "-j", str(os.cpu_count() or 2)])
        built = os.path.join(build_dir, "python", "peelcd")
        names = [n for n in os.listdir(built) if n.startswith("_peelcd") and n.endswith(".so")] if os.path.isdir(built) else []
        if not names:
            raise RuntimeError("peelcd: no _peelcd*.so in " + built + " (build the target _peelcd there)")
        target = self.get_ext_fullpath(ext.name)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copyfile(os.path.join(built, names[0]), target)


setup(version=version(), ext_modules=[Extension("peelcd._peelcd", sources=[])], cmdclass={"build_ext": CMakeBuild},
      options={"build": {"build_base": os.path.join("build", "setuptools")}, "egg_info": {"egg_base": "build"}})
