"""setuptools glue for pyproject.toml: builds modules/python with CMake and packages build/python/yawdepth.

No download at build time: cmake, the compiler, pybind11 and the libraries come from the system
(tools/bootstrap.sh). See pyproject.toml for the command and the environment variables.
"""
import os
import shlex
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

HERE = os.path.dirname(os.path.abspath(__file__))


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        tree = os.environ.get("YAWDEPTH_BUILD_DIR") or os.path.join(os.path.abspath(self.build_temp), "cmake")
        jobs = os.environ.get("JOBS", str(os.cpu_count() or 1))
        configure = ["cmake", "-S", HERE, "-B", tree, "-DCMAKE_BUILD_TYPE=Release", "-DYAWDEPTH_PYTHON=ON",
                     f"-DPython3_EXECUTABLE={sys.executable}"]
        if not os.environ.get("YAWDEPTH_BUILD_DIR"):
            configure += ["-DYAWDEPTH_BUILD_TESTS=OFF", "-DYAWDEPTH_BUILD_BENCHMARKS=OFF",
                          "-DYAWDEPTH_BUILD_EXAMPLES=OFF", "-DYAWDEPTH_BUILD_TOOLS=OFF", "-DCMAKE_UNITY_BUILD=ON"]
        configure += shlex.split(os.environ.get("CMAKE_ARGS", ""))
        subprocess.check_call(configure)
        subprocess.check_call(["cmake", "--build", tree, "--target", "yawdepth_python", "-j", jobs])
        package = os.path.join(tree, "python", "yawdepth")
        if not os.path.isdir(package):
            sys.exit("yawdepth: the Python module was not configured (pybind11-dev, python3-dev missing?)")
        out = os.path.join(os.path.abspath(self.build_lib), "yawdepth")
        shutil.rmtree(out, ignore_errors=True)
        shutil.copytree(package, out)


setup(packages=[], ext_modules=[Extension("yawdepth._yawdepth", sources=[])], cmdclass={"build_ext": CMakeBuild},
      zip_safe=False)
