"""Builds geojcbb._core from the repository's sources with the system's C++ compiler (setuptools
only: no CMake, no download). Objects and egg-info go to a scratch directory, never next to the
sources. Metadata: pyproject.toml. docs/python.md."""
import os
import shutil
import subprocess
import tempfile

from setuptools import Extension, setup

HERE = os.path.dirname(os.path.abspath(__file__))
os.chdir(HERE)  # the relative source paths below
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))


def eigen_include():
    try:
        out = subprocess.run(["pkg-config", "--cflags-only-I", "eigen3"], capture_output=True, text=True, check=True)
        return [p[2:] for p in out.stdout.split() if p.startswith("-I")]
    except (OSError, subprocess.CalledProcessError):
        return ["/usr/include/eigen3"]


def pybind11_include():
    try:
        import pybind11  # python3-pybind11, if installed
        return [pybind11.get_include()]
    except ImportError:
        return []  # pybind11-dev's headers are in /usr/include


ext = Extension(
    "geojcbb._core",
    # Relative to this folder (setuptools refuses absolute source paths); the objects of ../sim land
    # under the scratch build_base below, not beside the sources.
    sources=["geojcbb_py.cpp", os.path.join("..", "sim", "sim.cpp")],
    include_dirs=[os.path.join(ROOT, "firmware_lib", "include"), os.path.join(ROOT, "protocol", "include"),
                  os.path.join(ROOT, "host_tools", "sim", "include")] + eigen_include() + pybind11_include(),
    define_macros=[("EIGEN_STACK_ALLOCATION_LIMIT", "0")],
    extra_compile_args=["-std=c++17", "-O2", "-ffp-contract=off", "-fvisibility=hidden"],
    language="c++",
)

SCRATCH = tempfile.mkdtemp(prefix="geojcbb_build_")
try:
    setup(ext_modules=[ext], options={"build": {"build_base": SCRATCH}, "egg_info": {"egg_base": SCRATCH}})
finally:
    shutil.rmtree(SCRATCH, ignore_errors=True)
