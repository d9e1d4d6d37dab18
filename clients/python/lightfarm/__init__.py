"""lightfarm: a Python client of the lightfarm render farm (docs/python.md).

    import lightfarm

    with lightfarm.Client("127.0.0.1:7070", token_file="alice.token") as farm:
        job_id = farm.submit("tests/scenes/cornell_box.json", spp=16, resolution=(64, 64))
        for progress in farm.watch(job_id):
            print(f"{progress.state.name} {progress.fraction:.0%}")
        farm.fetch(job_id, "cornell.exr")

The gRPC stubs (lightfarm.v1) are generated from proto/ when the repository is built; the
importable package is build/python/lightfarm.
"""

from .client import (DEFAULT_SERVER, METHODS, BlockedWorker, Client, Job, JobState, LogLine,
                     Progress, Task, Worker, load_token)
from .errors import (Aborted, AlreadyExists, Cancelled, DeadlineExceeded, FailedPrecondition,
                     Internal, InvalidArgument, LightfarmError, NotFound, OutOfRange,
                     PermissionDenied, ResourceExhausted, TlsError, Unauthenticated, Unavailable,
                     Unimplemented)
from .preview import exr_to_png
from .scene import scene_files
from .shot import FrameRange, frame_path, parse_frames

__all__ = [
    "BlockedWorker", "Client", "Job", "JobState", "LogLine", "Progress", "Task", "Worker",
    "DEFAULT_SERVER", "METHODS", "load_token", "scene_files", "exr_to_png", "FrameRange",
    "frame_path", "parse_frames", "LightfarmError", "Aborted", "AlreadyExists",
    "Cancelled", "DeadlineExceeded", "FailedPrecondition", "Internal", "InvalidArgument",
    "NotFound", "OutOfRange", "PermissionDenied", "ResourceExhausted", "TlsError",
    "Unauthenticated", "Unavailable", "Unimplemented",
]
