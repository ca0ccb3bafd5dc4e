"""The standard gRPC health check (grpc.health.v1.Health/Check) that pathd
serves, for probes and start-up waits.

Debian ships no Python stubs for grpc.health.v1 (grpcio-health-checking is
not packaged), and stubs generated under the module path grpc/health/v1
would shadow grpcio's own `grpc` package. So the two messages are built here
from their descriptor, in a private descriptor pool: a program that also
imports grpc_health from PyPI gets no duplicate-symbol clash.
"""

from __future__ import annotations

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

HEALTH_CHECK_METHOD = "/grpc.health.v1.Health/Check"


def _message_classes():
    field = descriptor_pb2.FieldDescriptorProto
    file = descriptor_pb2.FileDescriptorProto(
        name="pathd_client/grpc_health_v1.proto", package="grpc.health.v1",
        syntax="proto3")
    request = file.message_type.add(name="HealthCheckRequest")
    request.field.add(name="service", number=1, type=field.TYPE_STRING,
                      label=field.LABEL_OPTIONAL)
    response = file.message_type.add(name="HealthCheckResponse")
    status = response.enum_type.add(name="ServingStatus")
    for number, name in enumerate(("UNKNOWN", "SERVING", "NOT_SERVING", "SERVICE_UNKNOWN")):
        status.value.add(name=name, number=number)
    response.field.add(name="status", number=1, type=field.TYPE_ENUM,
                       type_name=".grpc.health.v1.HealthCheckResponse.ServingStatus",
                       label=field.LABEL_OPTIONAL)
    pool = descriptor_pool.DescriptorPool()
    pool.Add(file)
    classes = []
    for name in ("grpc.health.v1.HealthCheckRequest", "grpc.health.v1.HealthCheckResponse"):
        descriptor = pool.FindMessageTypeByName(name)
        if hasattr(message_factory, "GetMessageClass"):  # protobuf >= 4.22
            classes.append(message_factory.GetMessageClass(descriptor))
        else:
            classes.append(message_factory.MessageFactory(pool).GetPrototype(descriptor))
    return classes


HealthCheckRequest, HealthCheckResponse = _message_classes()


def status_name(response) -> str:
    """"SERVING", "NOT_SERVING", "SERVICE_UNKNOWN" or "UNKNOWN"."""
    return response.DESCRIPTOR.enum_types_by_name["ServingStatus"].values_by_number[
        response.status].name
