"""Finds and imports the generated stubs (localizer/v1/localizer_pb2*.py).

Looked for, in order: the directory named by the environment variable LOCALIZER_PY_GEN, the
``gen`` directory beside this package (the build tree's clients/python/gen), and finally
whatever ``import localizer.v1`` finds on sys.path already.
"""
import os
import sys
from pathlib import Path

__all__ = ["pb", "pb_grpc", "GEN_DIR"]

_STUB = Path("localizer") / "v1" / "localizer_pb2.py"


def _gen_dir():
    env = os.environ.get("LOCALIZER_PY_GEN")
    if env:
        if not (Path(env) / _STUB).is_file():
            raise ImportError(f"LOCALIZER_PY_GEN={env!r} holds no {_STUB}; build the CMake "
                              "target localizer_python and point it at <build>/clients/python/gen")
        return env
    beside = Path(__file__).resolve().parent.parent / "gen"
    return str(beside) if (beside / _STUB).is_file() else None


GEN_DIR = _gen_dir()
if GEN_DIR and GEN_DIR not in sys.path:
    sys.path.insert(0, GEN_DIR)  # the grpc stub imports "localizer.v1.localizer_pb2"

try:
    from localizer.v1 import localizer_pb2 as pb  # noqa: E402
    from localizer.v1 import localizer_pb2_grpc as pb_grpc  # noqa: E402
except ImportError as e:  # pragma: no cover - message only
    raise ImportError("localizer_client: generated stubs not found; build the CMake target "
                      "localizer_python (they land in <build>/clients/python/gen) or set "
                      "LOCALIZER_PY_GEN to that directory") from e
