"""A generic gRPC client lists rdmeshd's services and calls them through server reflection only.

The client knows nothing of rdmesh's or health's protos: it has stubs for the reflection
protocol alone (protos/reflection.proto, compiled here with protoc) and builds every other
message type from the descriptors the server sends.
"""

import importlib
import subprocess
import sys

import grpc
import pytest
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

from conftest import PROTOC, REPO


@pytest.fixture(scope="module")
def reflection(tmp_path_factory):
    out = tmp_path_factory.mktemp("reflection_stubs")
    proto_dir = REPO / "tests" / "python" / "protos"
    subprocess.run([PROTOC, "-I", str(proto_dir), "--python_out", str(out),
                    "--grpc_python_out", str(out),
                    "--plugin=protoc-gen-grpc_python=/usr/bin/grpc_python_plugin",
                    "reflection.proto"], check=True)
    sys.path.insert(0, str(out))
    try:
        return (importlib.import_module("reflection_pb2"),
                importlib.import_module("reflection_pb2_grpc"))
    finally:
        sys.path.remove(str(out))


def _ask(stub, pb2, **request):
    responses = list(stub.ServerReflectionInfo(iter([pb2.ServerReflectionRequest(**request)]),
                                               timeout=10))
    assert len(responses) == 1
    response = responses[0]
    assert not response.HasField("error_response"), response.error_response.error_message
    return response


def _message_class(pool, name):
    descriptor = pool.FindMessageTypeByName(name)
    if hasattr(message_factory, "GetMessageClass"):
        return message_factory.GetMessageClass(descriptor)
    return message_factory.MessageFactory(pool).GetPrototype(descriptor)


def _pool_for(stub, pb2, symbol):
    """A fresh descriptor pool holding the file that defines `symbol` and its dependencies."""
    pool = descriptor_pool.DescriptorPool()
    pending = [_ask(stub, pb2, file_containing_symbol=symbol)]
    files = {}
    while pending:
        for blob in pending.pop().file_descriptor_response.file_descriptor_proto:
            file = descriptor_pb2.FileDescriptorProto.FromString(blob)
            if file.name in files:
                continue
            files[file.name] = file
            for dependency in file.dependency:
                if dependency not in files:
                    pending.append(_ask(stub, pb2, file_by_filename=dependency))
    added = set()

    def add(name):
        if name in added:
            return
        for dependency in files[name].dependency:
            add(dependency)
        pool.Add(files[name])
        added.add(name)

    for name in files:
        add(name)
    return pool


def _call_unary(channel, pool, service, method_name, request_fields):
    method = pool.FindServiceByName(service).FindMethodByName(method_name)
    request_class = _message_class(pool, method.input_type.full_name)
    response_class = _message_class(pool, method.output_type.full_name)
    call = channel.unary_unary("/%s/%s" % (service, method_name),
                               request_serializer=request_class.SerializeToString,
                               response_deserializer=response_class.FromString)
    return call(request_class(**request_fields), timeout=10)


def test_list_and_call_every_service_through_reflection(daemon, reflection):
    pb2, pb2_grpc = reflection
    with grpc.insecure_channel(daemon.address) as channel:
        stub = pb2_grpc.ServerReflectionStub(channel)
        listed = {s.name for s in _ask(stub, pb2, list_services="").list_services_response.service}
        assert {"rdmesh.v1.Rdmesh", "grpc.health.v1.Health",
                "grpc.reflection.v1alpha.ServerReflection"} <= listed

        rdmesh = _pool_for(stub, pb2, "rdmesh.v1.Rdmesh")
        methods = {m.name for m in rdmesh.FindServiceByName("rdmesh.v1.Rdmesh").methods}
        assert methods == {"UploadModel", "GetModelInfo", "Mesh", "GetServerStatus"}
        status = _call_unary(channel, rdmesh, "rdmesh.v1.Rdmesh", "GetServerStatus", {})
        assert status.serving and status.max_jobs == 2
        with pytest.raises(grpc.RpcError) as error:  # a real method, answering a real error
            _call_unary(channel, rdmesh, "rdmesh.v1.Rdmesh", "GetModelInfo",
                        {"model_id": "0" * 64})
        assert error.value.code() == grpc.StatusCode.NOT_FOUND

        health = _pool_for(stub, pb2, "grpc.health.v1.Health")
        answer = _call_unary(channel, health, "grpc.health.v1.Health", "Check",
                             {"service": "rdmesh.v1.Rdmesh"})
        status_enum = answer.DESCRIPTOR.fields_by_name["status"].enum_type
        assert status_enum.values_by_number[answer.status].name == "SERVING"
