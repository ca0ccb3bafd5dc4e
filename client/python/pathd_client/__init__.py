"""Python client for pathd, the gRPC path-planning daemon.

    from pathd_client import PathdClient
    with PathdClient("127.0.0.1:50051") as client:
        client.create_map("room", ["....", ".@@.", "...."])
        print(client.plan("room", (0, 0), (3, 2)).path)

Install it with pip (`pip install ./client/python`: the gRPC stubs of
package pathd.v1 are generated while it builds), or put the CMake build's
build/client/python on PYTHONPATH. See docs/python.md. The package:
client.py (PathdClient), streams.py (MapWatch, NavigationSession,
PlanStream, PlanBatch), values.py (value types and conversions), errors.py
(PathdError and its subclasses), channel.py (TLS and tokens), health.py
(the gRPC health check), map_files.py (map files as CreateMap sources).
"""

from pathd_client.channel import make_channel
from pathd_client.client import PathdClient
from pathd_client.errors import (
    AbortedError,
    AlreadyExistsError,
    DeadlineExceededError,
    FailedPreconditionError,
    InvalidArgumentError,
    NotFoundError,
    PathdError,
    PermissionDeniedError,
    ResourceExhaustedError,
    UnauthenticatedError,
    UnavailableError,
    make_error,
)
from pathd_client.streams import (BatchAnswer, MapWatch, NavigationSession,
                                  PlanBatch, PlanStream)
from pathd_client.values import (
    DEFAULT_TIMEOUT,
    FREE,
    INSCRIBED,
    LETHAL,
    MAP_HEADER,
    UNKNOWN,
    CacheStats,
    CacheStatsResult,
    Cell,
    CellPose,
    Change,
    ChangedRect,
    CostToGoResult,
    Origin,
    PathCheck,
    PlanProgress,
    WorldPoint,
    WorldPose,
    VelocityCommand,
    FleetPlanResult,
    FleetSessionState,
    IsochroneResult,
    MapCells,
    MapEvent,
    MapInfo,
    NavigateUpdate,
    NearestResult,
    PlanResult,
    SetCell,
    SessionInfo,
    SetRect,
    TableResult,
    TripResult,
    UpdateResult,
    decode_packed_path,
    path_frame_cell_center,
    plan_options,
    plan_request,
)

__all__ = [
    "DEFAULT_TIMEOUT", "FREE", "INSCRIBED", "LETHAL", "MAP_HEADER", "UNKNOWN",
    "AbortedError", "AlreadyExistsError", "Cell", "Change", "ChangedRect",
    "DeadlineExceededError", "FailedPreconditionError", "InvalidArgumentError",
    "MapCells", "MapEvent", "MapInfo", "MapWatch", "NavigateUpdate",
    "NavigationSession", "NotFoundError", "VelocityCommand", "PathdClient", "PathdError",
    "PlanResult", "ResourceExhaustedError", "SetCell", "SetRect",
    "UnavailableError", "UpdateResult", "WorldPose", "make_error", "plan_options",
    "TableResult", "NearestResult", "TripResult", "IsochroneResult",
    "FleetPlanResult", "FleetSessionState", "BatchAnswer", "CacheStats", "CacheStatsResult", "CellPose",
    "CostToGoResult", "Origin", "PathCheck", "PermissionDeniedError", "PlanBatch",
    "PlanProgress", "PlanStream", "UnauthenticatedError", "WorldPoint",
    "make_channel", "plan_request", "SessionInfo", "decode_packed_path",
    "path_frame_cell_center",
]
