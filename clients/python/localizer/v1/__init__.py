"""The wire contract localizer.v1, as generated Python stubs.

``localizer_pb2`` (messages) and ``localizer_pb2_grpc`` (the service stub) are written here at
build time from proto/localizer/v1/localizer.proto, so that the proto package ``localizer.v1``
and this Python package are the same name: the grpc stub's own
``from localizer.v1 import localizer_pb2`` then resolves inside the installed package.
"""
