"""Builds the compiled module softkin._softkin with CMake for `pip install --no-build-isolation .`
(pyproject.toml holds the metadata). The CMake build is Release, without tests or benchmarks,
in setuptools' build_temp; set SOFTKIN_CMAKE_BUILD_DIR to an already configured SoftKin build
tree to reuse it instead, and SOFTKIN_JOBS for the parallel jobs (default: all cores)."""

import glob
import os
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = os.path.dirname(os.path.abspath(__file__))


class CMakeExtension(Extension):
    def __init__(self, name):
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build_dir = os.environ.get("SOFTKIN_CMAKE_BUILD_DIR")
        jobs = os.environ.get("SOFTKIN_JOBS", str(os.cpu_count() or 1))
        if not build_dir:
            build_dir = os.path.abspath(os.path.join(self.build_temp, "cmake"))
            self.announce(f"softkin: configuring with CMake in {build_dir}", level=2)
            subprocess.check_call([
                "cmake", "-S", ROOT, "-B", build_dir, "-DCMAKE_BUILD_TYPE=Release",
                "-DSOFTKIN_BUILD_TESTS=OFF", "-DSOFTKIN_BUILD_BENCH=OFF", "-DSOFTKIN_PYTHON=ON",
                f"-DPython3_EXECUTABLE={sys.executable}"])
        subprocess.check_call(["cmake", "--build", build_dir, "--target", "softkin_python",
                               "-j", jobs])
        built = glob.glob(os.path.join(build_dir, "python", "softkin", "_softkin*.so"))
        if len(built) != 1:
            raise RuntimeError(f"softkin: expected one _softkin*.so in {build_dir}/python/softkin, "
                               f"found {built}; is pybind11-dev installed (scripts/setup.sh)?")
        target = self.get_ext_fullpath(ext.name)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copyfile(built[0], target)


setup(ext_modules=[CMakeExtension("softkin._softkin")], cmdclass={"build_ext": CMakeBuild})
