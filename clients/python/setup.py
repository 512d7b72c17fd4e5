"""Build steps of the package ``localizer`` that pyproject.toml cannot state.

- The version is read from the top CMakeLists.txt's ``project(localizer VERSION x.y.z)``, the
  project's one version source (CMake writes the same number into its build-tree copy), and
  written into the package as ``localizer/_version.py``.
- The gRPC stubs ``localizer/v1/localizer_pb2.py``, ``localizer_pb2_grpc.py`` (and the
  ``.pyi``) are generated from proto/localizer/v1/localizer.proto by the system protoc with
  grpc_python_plugin, as the CMake target localizer_python does (why not python3-grpc-tools:
  clients/python/CMakeLists.txt). PROTOC and GRPC_PYTHON_PLUGIN override where they are.
- The compiled submodule ``localizer.engine`` (the engine's pybind11 bindings,
  clients/python/engine_module) is taken from the CMake build, not compiled here: the file
  ``<build>/clients/python/localizer/engine<EXT_SUFFIX>`` of the build directory
  ``LOCALIZER_BUILD_DIR`` (default: ``<repo>/build``, the README's build). When that build
  directory is configured but the module is missing or older than its sources, setup.py runs
  ``cmake --build <build> --target localizer_engine_py`` first. With no configured build the
  package is built without it (a warning says so; ``import localizer.engine`` then fails) —
  or, with ``LOCALIZER_REQUIRE_ENGINE=1``, the build fails. With the module the wheel is
  platform-specific (cp311-cp311-linux_x86_64) and, like the build, tuned for the machine
  that compiled it (-march=native unless configured with -DLOCALIZER_NATIVE=OFF).
- setuptools' scratch directories (build/, localizer.egg-info) go to a temporary directory,
  not into clients/python (a second "build" beside CMake's would mislead, and stale modules
  left there would end up in the next wheel).

Both inputs lie outside this directory, so the package builds from a clone of the repository
(pip builds a local directory in place), not from an sdist.
"""
import atexit
import os
import sys
import sysconfig
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

from setuptools import Distribution, setup
from setuptools.command.build_py import build_py
from setuptools.errors import ExecError, FileError

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
CMAKE_LISTS = REPO / "CMakeLists.txt"
PROTO_ROOT = REPO / "proto"
PROTO = "localizer/v1/localizer.proto"
INSTALL_HINT = ("on Debian: apt-get install protobuf-compiler protobuf-compiler-grpc "
                "(or set PROTOC / GRPC_PYTHON_PLUGIN to the programs)")


def project_version():
    """x.y.z of ``project(localizer VERSION x.y.z ...)`` in the top CMakeLists.txt."""
    if not CMAKE_LISTS.is_file():
        raise FileError(f"{CMAKE_LISTS} not found: build the localizer package from a clone of "
                        "the repository (pip install ./clients/python)")
    match = re.search(r"project\(\s*localizer\s+VERSION\s+([0-9]+(?:\.[0-9]+)*)",
                      CMAKE_LISTS.read_text(encoding="utf-8"))
    if not match:
        raise FileError(f"{CMAKE_LISTS}: no `project(localizer VERSION x.y.z)` line")
    return match.group(1)


def find_program(env, name, default=None):
    path = os.environ.get(env) or shutil.which(name) or (default if default and os.access(default, os.X_OK) else None)
    if not path:
        raise ExecError(f"{name} not found, needed to generate the gRPC stubs; {INSTALL_HINT}")
    return path


def generate_stubs(out_dir):
    """Runs protoc with grpc_python_plugin on the contract into ``out_dir`` (the build's lib)."""
    if not (PROTO_ROOT / PROTO).is_file():
        raise FileError(f"{PROTO_ROOT / PROTO} not found: build the localizer package from a "
                        "clone of the repository")
    protoc = find_program("PROTOC", "protoc")
    plugin = find_program("GRPC_PYTHON_PLUGIN", "grpc_python_plugin", "/usr/bin/grpc_python_plugin")
    command = [protoc, f"--proto_path={PROTO_ROOT}", f"--python_out={out_dir}",
               f"--pyi_out={out_dir}", f"--grpc_python_out={out_dir}",
               f"--plugin=protoc-gen-grpc_python={plugin}", str(PROTO_ROOT / PROTO)]
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        raise ExecError(f"protoc failed ({done.returncode}): {' '.join(command)}\n{done.stderr}")


def engine_module():
    """The built localizer.engine for this interpreter, or None (see the docstring above)."""
    build_dir = Path(os.environ.get("LOCALIZER_BUILD_DIR") or REPO / "build")
    module = build_dir / "clients" / "python" / "localizer" / ("engine" + sysconfig.get_config_var("EXT_SUFFIX"))
    if (build_dir / "CMakeCache.txt").is_file():
        # The target is up to date in a second when nothing changed; a stale module is rebuilt.
        done = subprocess.run(["cmake", "--build", str(build_dir), "--target", "localizer_engine_py"],
                              capture_output=True, text=True)
        unknown_target = "unknown target" in done.stderr or "No rule to make target" in done.stderr
        if done.returncode != 0 and not unknown_target:  # unknown: configured without pybind11
            raise ExecError(f"cmake --build {build_dir} --target localizer_engine_py failed "
                            f"({done.returncode}):\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}")
    if module.is_file():
        return module
    message = (f"localizer.engine not found at {module}: build it first (docs/PYTHON.md: cmake -S . -B build; "
               "cmake --build build --target localizer_engine_py; Debian: pybind11-dev) or set "
               "LOCALIZER_BUILD_DIR to the build directory")
    if os.environ.get("LOCALIZER_REQUIRE_ENGINE") == "1":
        raise FileError(message)
    print(f"warning: {message}; the package is built without it", file=sys.stderr)
    return None


ENGINE_MODULE = engine_module()


class BinaryDistribution(Distribution):
    """A wheel holding the compiled localizer.engine is tagged for this interpreter and platform."""

    def has_ext_modules(self):
        return ENGINE_MODULE is not None


class BuildPy(build_py):
    """Copies the package, then adds the generated stubs, _version.py and localizer.engine."""

    def run(self):
        super().run()
        if self.dry_run:
            return
        generate_stubs(self.build_lib)
        if ENGINE_MODULE is not None:
            shutil.copy2(ENGINE_MODULE, Path(self.build_lib) / "localizer" / ENGINE_MODULE.name)
        version_py = Path(self.build_lib) / "localizer" / "_version.py"
        version_py.write_text("# Generated by setup.py from CMake's project(VERSION); do not edit.\n"
                              f'__version__ = "{self.distribution.get_version()}"\n',
                              encoding="utf-8")


def scratch_dir():
    """A temporary directory for setuptools' build/ and egg-info, removed at exit."""
    path = tempfile.mkdtemp(prefix="localizer-pybuild-")
    atexit.register(shutil.rmtree, path, ignore_errors=True)
    return path


SCRATCH = scratch_dir()
setup(version=project_version(), cmdclass={"build_py": BuildPy}, distclass=BinaryDistribution,
      options={"build": {"build_base": os.path.join(SCRATCH, "build")},
               "egg_info": {"egg_base": SCRATCH}})
