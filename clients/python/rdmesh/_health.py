"""grpc.health.v1 messages, built from a descriptor at import time.

grpcio's own health module (grpcio-health-checking) is not packaged in Debian, and generating
stubs for grpc/health/v1/health.proto would clash with the ``grpc`` package name, so the two
small messages of the standard health protocol are described here directly.
"""

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

_F = descriptor_pb2.FieldDescriptorProto


def _build():
    file = descriptor_pb2.FileDescriptorProto(
        name="rdmesh_client/grpc_health_v1.proto", package="grpc.health.v1", syntax="proto3")
    request = file.message_type.add(name="HealthCheckRequest")
    request.field.add(name="service", number=1, type=_F.TYPE_STRING, label=_F.LABEL_OPTIONAL)
    response = file.message_type.add(name="HealthCheckResponse")
    status = response.enum_type.add(name="ServingStatus")
    for number, name in enumerate(["UNKNOWN", "SERVING", "NOT_SERVING", "SERVICE_UNKNOWN"]):
        status.value.add(name=name, number=number)
    response.field.add(name="status", number=1, type=_F.TYPE_ENUM, label=_F.LABEL_OPTIONAL,
                       type_name=".grpc.health.v1.HealthCheckResponse.ServingStatus")
    pool = descriptor_pool.DescriptorPool()
    pool.Add(file)

    def message_class(name):
        descriptor = pool.FindMessageTypeByName(name)
        if hasattr(message_factory, "GetMessageClass"):
            return message_factory.GetMessageClass(descriptor)
        return message_factory.MessageFactory(pool).GetPrototype(descriptor)

    return (message_class("grpc.health.v1.HealthCheckRequest"),
            message_class("grpc.health.v1.HealthCheckResponse"))


HealthCheckRequest, HealthCheckResponse = _build()
CHECK_METHOD = "/grpc.health.v1.Health/Check"


def status_name(response):
    """The ServingStatus name of a HealthCheckResponse, e.g. "SERVING"."""
    return HealthCheckResponse.DESCRIPTOR.enum_types_by_name["ServingStatus"].values_by_number[
        response.status].name
