"""rovermap from Python: Zhang's iterative point matching, the mapping pipeline of
`rovermap replay` (registered trajectory, DEM, OctoMap, drift report) and the trajectory and DEM
metrics of `rovermap eval`, on numpy arrays.

    import rovermap
    result = rovermap.register(source_points, target_points, max_iterations=50)
    mapper = rovermap.Mapper("datasets/sim_tiny_stereo")
    for frame in rovermap.Sequence("datasets/sim_tiny_stereo"):
        mapper.process_frame(frame)
    summary = mapper.write_outputs("out/py")

Errors carry over from the commands: a bad key, value or array raises ValueError naming it, a
file that cannot be read or written raises OSError naming the file.
"""
import os as _os

# OpenMP threads that finish a parallel loop first spin for the others by default, taking the
# core a partner needs on a small machine; the command runs with a passive wait for the same
# reason (apps/main.cpp). libgomp reads the variable when it is loaded, i.e. at the import below,
# and a user's own setting is kept.
_os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

from ._rovermap import (  # noqa: E402
    __version__,
    Camera,
    ElevationMap,
    Frame,
    FrameResult,
    Mapper,
    RegistrationResult,
    Sequence,
    eval,
    read_points,
    register,
)

__all__ = [
    "Camera",
    "ElevationMap",
    "Frame",
    "FrameResult",
    "Mapper",
    "RegistrationResult",
    "Sequence",
    "eval",
    "read_points",
    "register",
]
