"""The generated gRPC stubs, imported once here so the rest of the package has one place to
fail with a useful message when they are missing.

The stubs are not in the source tree: ``localizer/v1/localizer_pb2.py`` and
``localizer_pb2_grpc.py`` are generated from ``proto/localizer/v1/localizer.proto`` by the
system protoc with /usr/bin/grpc_python_plugin, either by ``pip install ./clients/python``
(setup.py) or by the CMake target ``localizer_python`` (into ``<build>/clients/python``).
"""
try:
    from .v1 import localizer_pb2 as pb
    from .v1 import localizer_pb2_grpc as pb_grpc
except ImportError as e:  # pragma: no cover - message only
    raise ImportError(
        "localizer: the generated stubs localizer/v1/localizer_pb2*.py are missing. This is the "
        "source tree: install the package (pip install --no-build-isolation ./clients/python) or "
        "put <build>/clients/python on sys.path after building the CMake target localizer_python"
    ) from e

__all__ = ["pb", "pb_grpc"]
