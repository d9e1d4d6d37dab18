"""lightfarm.Client: the farm's JobService (proto/lightfarm/v1/job_service.proto) from Python."""

from __future__ import annotations

import dataclasses
import datetime
import enum
import hashlib
import math
import os
import secrets
import time
from typing import Dict, Iterable, Iterator, List, Optional, Sequence, Tuple, Union

import grpc

from . import errors
from .errors import InvalidArgument, LightfarmError
from .preview import TONEMAPS, exr_to_png
from .scene import check_scene_path, scene_files
from .shot import (DEFAULT_FPS, MAX_CHUNK, MAX_FPS, MAX_SHUTTER, MIN_FPS, FrameRange,
                   check_frame_pattern, check_range, frame_path, parse_frames)
from .v1 import common_pb2, job_service_pb2, job_service_pb2_grpc

pb = job_service_pb2

DEFAULT_SERVER = "127.0.0.1:7070"
CHUNK_BYTES = 1 << 20  # at most this much data per stream message (the wire's limit)

# Deadlines, as the C++ client's.
UNARY_SECONDS = 10.0
SUBMIT_SECONDS = 120.0  # the server loads the scene to check it
UPLOAD_SECONDS = 600.0
FETCH_SECONDS = 1800.0
WATCH_STREAM_SECONDS = 60.0  # one WatchJob stream; the watch goes on across them

# Keepalive as proto/src/channel.cc: a dead link is found within 15 s.
_CHANNEL_OPTIONS = [
    ("grpc.keepalive_time_ms", 10000),
    ("grpc.keepalive_timeout_ms", 5000),
    ("grpc.keepalive_permit_without_calls", 1),
    ("grpc.http2.max_pings_without_data", 0),
]

_AOVS = {"albedo": 1, "normal": 2, "depth": 4, "illuminance": 8}
_FILTERS = {"box": common_pb2.FILTER_BOX, "gaussian": common_pb2.FILTER_GAUSSIAN,
            "blackman-harris": common_pb2.FILTER_BLACKMAN_HARRIS}
_SAMPLERS = {"independent": common_pb2.SAMPLER_INDEPENDENT, "sobol": common_pb2.SAMPLER_SOBOL}
_LIGHT_SAMPLING = {"power": common_pb2.LIGHT_STRATEGY_POWER, "bvh": common_pb2.LIGHT_STRATEGY_BVH}
METHODS = ("path", "radiosity", "whitted", "light", "bdpt", "ppm")


class JobState(enum.Enum):
    """A job's state (lightfarm.v1.Job.State)."""
    UNSPECIFIED = 0
    QUEUED = 1     # no task leased yet
    RUNNING = 2    # some task leased or done
    SUCCEEDED = 3  # the result is written and fetchable
    FAILED = 4     # see Job.error
    CANCELLED = 5

    @property
    def final(self) -> bool:
        """True for SUCCEEDED, FAILED and CANCELLED: the job will not change any more."""
        return self in (JobState.SUCCEEDED, JobState.FAILED, JobState.CANCELLED)


@dataclasses.dataclass(frozen=True)
class BlockedWorker:
    """A worker blocklisted from a job (lightfarm.v1.BlockedWorker): its failures there."""
    worker: str
    failures: int
    last_error: str


@dataclasses.dataclass(frozen=True)
class Job:
    """A job as the server reports it (lightfarm.v1.Job; ``proto`` is the message itself)."""
    id: str
    name: str
    state: JobState
    error: str
    priority: int
    width: int
    height: int
    scene_hash: str
    tasks_total: int
    tasks_done: int
    tasks_running: int
    samples: int
    rays: int
    invalid_samples: int
    submitted_unix_ms: int
    started_unix_ms: int
    finished_unix_ms: int
    retries: int
    tasks_leased: int
    last_error: str
    owner: str
    tags: Tuple[str, ...]  # only workers having every one take it; () any worker
    max_workers: int       # at most this many workers at once; 0 no cap
    waiting_reason: str    # why no worker takes it, e.g. "waiting for a worker with tags gpu"
    proto: pb.Job = dataclasses.field(repr=False, compare=False)

    # Job management (issue 30).
    @property
    def blocklist(self) -> List["BlockedWorker"]:
        """The workers blocklisted from the job: they get none of its tasks any more."""
        return [BlockedWorker(b.worker, b.failures, b.last_error) for b in self.proto.blocklist]

    @property
    def after(self) -> Tuple[str, ...]:
        """Dependencies: the jobs it runs after."""
        return tuple(self.proto.after)

    @property
    def waiting_for(self) -> Tuple[str, ...]:
        """Of ``after``, those not ended yet while the job is queued."""
        return tuple(self.proto.waiting_for)

    @property
    def paused(self) -> bool:
        """Paused (``Client.pause``): a queued or running job that leases nothing new."""
        return self.proto.paused

    @property
    def max_attempts(self) -> int:
        return self.proto.max_attempts

    @property
    def blocklist_after(self) -> int:
        return self.proto.blocklist_after

    # History (issue 30): summed over its merged tasks, as their workers measured them.
    @property
    def cpu_seconds(self) -> float:
        return self.proto.cpu_seconds

    @property
    def render_seconds(self) -> float:
        return self.proto.render_seconds

    @property
    def params(self) -> common_pb2.RenderParams:
        """The render settings (lightfarm.v1.RenderParams)."""
        return self.proto.params

    @property
    def method(self) -> str:
        return self.proto.params.method or "path"

    @property
    def fraction(self) -> float:
        """Tasks done of all, 0..1 (1 once the job succeeded)."""
        if self.state == JobState.SUCCEEDED:
            return 1.0
        return self.tasks_done / self.tasks_total if self.tasks_total > 0 else 0.0

    @classmethod
    def from_proto(cls, m: pb.Job) -> "Job":
        values = {f.name: getattr(m, f.name) for f in dataclasses.fields(cls)
                  if f.name not in ("state", "proto", "tags")}
        return cls(state=JobState(m.state), proto=m, tags=tuple(m.tags), **values)


@dataclasses.dataclass(frozen=True)
class Progress:
    """One snapshot of a watched job: what ``Client.watch`` yields."""
    job_id: str
    state: JobState
    tasks_done: int
    tasks_total: int
    tasks_running: int
    fraction: float  # tasks_done / tasks_total, 0..1
    samples: int     # samples merged so far
    error: str       # why the job failed, once it has
    last_error: str  # the most recent task failure, while its task is retried
    job: Job = dataclasses.field(repr=False, compare=False)

    @property
    def final(self) -> bool:
        return self.state.final

    @classmethod
    def of(cls, job: Job) -> "Progress":
        return cls(job.id, job.state, job.tasks_done, job.tasks_total, job.tasks_running,
                   job.fraction, job.samples, job.error, job.last_error, job)


@dataclasses.dataclass(frozen=True)
class Worker:
    """A worker the server knows (lightfarm.v1.WorkerInfo): heard from within a lease, or
    offline (silent, listed until the server's --forget-workers-after)."""
    id: str
    name: str
    address: str
    version: str
    busy: bool
    job_id: str
    task_index: int
    seconds_since_seen: float
    tags: Tuple[str, ...]  # lightfarm-worker --tags
    # "idle", "busy", "disabled", "draining", "drained" or "offline"
    state: str
    last_seen_unix_ms: int

    @classmethod
    def from_proto(cls, m: pb.WorkerInfo) -> "Worker":
        # Busy: holds a task, whatever else it is (a disabled or draining worker's task goes on).
        return cls(m.id, m.name, m.address, m.version, bool(m.job_id), m.job_id, m.task_index,
                   m.seconds_since_seen, tuple(m.tags),
                   pb.WorkerInfo.State.Name(m.state).lower(), m.last_seen_unix_ms)


@dataclasses.dataclass(frozen=True)
class Task:
    """One task of a job (lightfarm.v1.TaskInfo); state and kind by name, e.g. "DONE", "TILE"."""
    index: int
    state: str
    kind: str
    x: int
    y: int
    width: int
    height: int
    samples: int
    attempts: int
    failures: int
    worker: str
    leased_unix_ms: int
    finished_unix_ms: int
    seconds: float
    last_error: str
    log_lines: int

    @classmethod
    def from_proto(cls, m: pb.TaskInfo) -> "Task":
        values = {f.name: getattr(m, f.name) for f in dataclasses.fields(cls)
                  if f.name not in ("state", "kind")}
        return cls(state=pb.TaskInfo.State.Name(m.state), kind=pb.TaskInfo.Kind.Name(m.kind),
                   **values)


@dataclasses.dataclass(frozen=True)
class LogLine:
    """A line a worker logged while running a task (lightfarm.v1.TaskLogLine)."""
    seq: int
    task_index: int
    attempt: int
    worker: str
    unix_ms: int
    level: str
    text: str

    @classmethod
    def from_proto(cls, m: pb.TaskLogLine) -> "LogLine":
        return cls(m.seq, m.task_index, m.attempt, m.worker, m.unix_ms, m.level, m.text)


def _read_text(path: str, what: str) -> str:
    try:
        with open(path, "r", encoding="utf-8") as f:
            return f.read()
    except OSError as e:
        raise InvalidArgument(f"{what} {path}: cannot be read ({e.strerror})") from None


def _read_pem(path: str, what: str) -> bytes:
    text = _read_text(path, what)
    if "-----BEGIN " not in text:
        raise InvalidArgument(f"{what} {path}: not a PEM file (no -----BEGIN line)")
    return text.encode()


def load_token(token: Optional[str] = None, token_file: Optional[str] = None) -> str:
    """The bearer token: ``token``, else the first line of ``token_file``, else the environment's
    LIGHTFARM_TOKEN, else "" (no token: a server without tokens on loopback)."""
    if token is not None:
        return token.strip()
    if token_file:
        first = _read_text(token_file, "token_file").split("\n", 1)[0].strip()
        if not first:
            raise InvalidArgument(f"token_file {token_file}: empty")
        return first
    return os.environ.get("LIGHTFARM_TOKEN", "").strip()


class _Backoff:
    """0.25 s, doubling up to 5 s, while the budget lasts (the C++ client's Backoff)."""

    def __init__(self, budget: float) -> None:
        self.budget = budget
        self.reset()

    def reset(self) -> None:
        self.waited = 0.0
        self.delay = 0.25

    def wait(self) -> bool:
        if self.waited + self.delay > self.budget:
            return False
        time.sleep(self.delay)
        self.waited += self.delay
        self.delay = min(2 * self.delay, 5.0)
        return True


class Client:
    """A connection to lightfarm-server's JobService.

    Args:
        server: HOST:PORT; default the environment's LIGHTFARM_SERVER, else 127.0.0.1:7070.
        token: the bearer token (sent as ``authorization: Bearer TOKEN`` on every call).
        token_file: a file whose first line is the token (used when ``token`` is None); without
            either, the environment's LIGHTFARM_TOKEN.
        tls_ca: PEM CA that signed the server's certificate: TLS on (default the environment's
            LIGHTFARM_TLS_CA). The server's name or address must be in its certificate.
        tls_cert, tls_key: a PEM client certificate and its key, for a server that asks for one
            (they need ``tls_ca``).
        retry_seconds: how long ``submit`` and ``watch`` ride out an unreachable server
            (restarting, say); 0 does not retry.

    Use it as a context manager, or call :meth:`close`::

        with lightfarm.Client(token_file="alice.token", tls_ca="ca.crt") as farm:
            job_id = farm.submit("scene.json", spp=64)
    """

    def __init__(self, server: Optional[str] = None, *, token: Optional[str] = None,
                 token_file: Optional[str] = None, tls_ca: Optional[str] = None,
                 tls_cert: Optional[str] = None, tls_key: Optional[str] = None,
                 retry_seconds: float = 60.0) -> None:
        self.server = server or os.environ.get("LIGHTFARM_SERVER") or DEFAULT_SERVER
        if tls_ca is None:
            tls_ca = os.environ.get("LIGHTFARM_TLS_CA") or None
        self._credentials: Optional[grpc.ChannelCredentials] = None
        if not tls_ca:
            if tls_cert or tls_key:
                raise InvalidArgument(
                    "tls_cert and tls_key need tls_ca: TLS is on with the server's CA")
        else:
            if bool(tls_cert) != bool(tls_key):
                raise InvalidArgument("tls_cert and tls_key go together")
            self._credentials = grpc.ssl_channel_credentials(
                root_certificates=_read_pem(tls_ca, "tls_ca"),
                private_key=_read_pem(tls_key, "tls_key") if tls_key else None,
                certificate_chain=_read_pem(tls_cert, "tls_cert") if tls_cert else None)
        token = load_token(token, token_file)
        self._metadata: Tuple[Tuple[str, str], ...] = (
            (("authorization", f"Bearer {token}"),) if token else ())
        self.retry_seconds = retry_seconds
        self._channel: Optional[grpc.Channel] = None
        self._stub: Optional[job_service_pb2_grpc.JobServiceStub] = None
        self._connect()

    # --- connection ---
    def _connect(self) -> None:
        """A new channel: after an outage a fresh one, as a channel that failed to connect fails
        calls fast for a while after the server is back."""
        if self._channel is not None:
            self._channel.close()
        if self._credentials is not None:
            self._channel = grpc.secure_channel(self.server, self._credentials,
                                                options=_CHANNEL_OPTIONS)
        else:
            self._channel = grpc.insecure_channel(self.server, options=_CHANNEL_OPTIONS)
        self._stub = job_service_pb2_grpc.JobServiceStub(self._channel)

    def close(self) -> None:
        """Closes the channel; the client is of no use afterwards."""
        if self._channel is not None:
            self._channel.close()
            self._channel = None

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _error(self, e: grpc.RpcError, call: str = "") -> LightfarmError:
        return errors.from_rpc_error(e, self.server, call, tls=self._credentials is not None)

    def _unary(self, method: str, request, timeout: float = UNARY_SECONDS):
        try:
            return getattr(self._stub, method)(request, timeout=timeout, metadata=self._metadata)
        except grpc.RpcError as e:
            raise self._error(e, method) from None

    # --- jobs ---
    def get(self, job_id: str) -> Job:
        """The job now. NotFound for an unknown id (or another submitter's job)."""
        return Job.from_proto(self._unary("GetJob", pb.GetJobRequest(job_id=job_id)))

    def list(self, *, page_size: int = 500, limit: Optional[int] = None) -> Iterator[Job]:
        """The server's jobs (a submitter's own only), newest first, fetching page after page
        as the iteration goes; ``limit`` stops after that many."""
        token = ""
        listed = 0
        while True:
            size = page_size if limit is None else min(page_size, limit - listed)
            if size <= 0:
                return
            resp = self._unary("ListJobs", pb.ListJobsRequest(page_size=size, page_token=token))
            for m in resp.jobs:
                yield Job.from_proto(m)
            listed += len(resp.jobs)
            token = resp.next_page_token
            if not token:
                return

    def cancel(self, job_id: str) -> Job:
        """Stops a queued or running job (workers drop its tasks within about a second) and
        returns it. FailedPrecondition when it has already ended."""
        return Job.from_proto(self._unary("CancelJob", pb.CancelJobRequest(job_id=job_id)))

    def delete(self, job_id: str) -> None:
        """Removes an ended job, its record and its result. FailedPrecondition for a job that
        has not ended (cancel it first)."""
        self._unary("DeleteJob", pb.DeleteJobRequest(job_id=job_id))

    def set_priority(self, job_id: str, priority: int) -> Job:
        """Changes a queued or running job's priority (higher runs first): the job's owner or an
        admin. FailedPrecondition for a job that has ended."""
        return Job.from_proto(self._unary(
            "SetJobPriority", pb.SetJobPriorityRequest(job_id=job_id, priority=priority)))

    # Job management (issue 30).
    def requeue(self, job_id: str, frames: Optional[str] = None, failed: bool = True) -> Job:
        """``lightfarm requeue``. With ``failed`` (the default) and no ``frames``: puts the job's
        failed tasks back in the queue with their failures reset and clears its blocklist; a
        failed or cancelled job is queued again and renders on from the tasks it had done
        (FailedPrecondition for a succeeded job). ``frames`` ("A-B[:STEP]", submit's --frames
        syntax): those frames of an ended shot, a succeeded one too, are rendered again from
        scratch; InvalidArgument for frames outside the shot or a still."""
        if frames is None and not failed:
            raise ValueError("requeue: nothing to requeue (failed=False and no frames)")
        return Job.from_proto(self._unary(
            "RequeueJob", pb.RequeueJobRequest(job_id=job_id, frames=frames or "")))

    def pause(self, job_id: str) -> Job:
        """Pauses a queued or running job: it leases nothing new, its running tasks finish
        (``lightfarm pause``); it stays paused across a restart. FailedPrecondition once ended."""
        return Job.from_proto(self._unary("PauseJob", pb.PauseJobRequest(job_id=job_id)))

    def resume(self, job_id: str) -> Job:
        """Resumes a paused job (``lightfarm resume``)."""
        return Job.from_proto(self._unary("ResumeJob", pb.ResumeJobRequest(job_id=job_id)))

    # History (issue 30).
    def stats(self, *, since: Union[None, datetime.datetime, datetime.timedelta] = None,
              owner: str = "") -> Dict[str, object]:
        """The farm's history as ``lightfarm stats`` prints it: work that ended ``since`` (a
        time, naive ones read as UTC, or a span before now; None: all the history kept), only
        ``owner``'s jobs when given. An admin sees everyone's, a submitter their own jobs (asking
        for another owner's is PermissionDenied). Returns plain dicts: ``{"since": datetime or
        None, "owners": [...], "workers": [...]}``, each row with the keys of the wire's
        OwnerStats and WorkerStats (docs/farm.md, History)."""
        if isinstance(since, datetime.timedelta):
            since = datetime.datetime.now(datetime.timezone.utc) - since
        if since is not None and since.tzinfo is None:
            since = since.replace(tzinfo=datetime.timezone.utc)
        req = pb.GetStatsRequest(owner=owner)
        if since is not None:
            req.since_unix_ms = int(since.timestamp() * 1000)
        resp = self._unary("GetStats", req)

        def row(m) -> Dict[str, object]:
            return {f.name: getattr(m, f.name) for f in m.DESCRIPTOR.fields}

        return {
            "since": (datetime.datetime.fromtimestamp(resp.since_unix_ms / 1000,
                                                      datetime.timezone.utc)
                      if resp.since_unix_ms else None),
            "owners": [row(o) for o in resp.owners],
            "workers": [row(w) for w in resp.workers],
        }

    def depend(self, job_id: str, after: Sequence[str]) -> Job:
        """Makes a queued job also run after the jobs ``after`` (``lightfarm depend``): the job's
        owner or an admin. FailedPrecondition for a cycle (its message names it), a job not
        queued, or a dependency that failed or was cancelled; NotFound for an unknown id."""
        if isinstance(after, str):
            raise InvalidArgument(f"after {after!r}: a list of job ids, e.g. [{after!r}]")
        return Job.from_proto(self._unary(
            "AddJobDependencies", pb.AddJobDependenciesRequest(job_id=job_id, after=list(after))))

    def workers(self) -> List[Worker]:
        """The workers the server heard from within a lease."""
        resp = self._unary("ListWorkers", pb.ListWorkersRequest())
        return [Worker.from_proto(w) for w in resp.workers]

    def set_worker_state(self, name: str, state: str) -> List[Worker]:
        """Admins: ``state`` "disable" (no new task; the current one goes on), "drain" (finish
        the current task, then none) or "enable" the workers named ``name`` (or the one whose id
        it is). Kept by name across server restarts. Returns those workers in their new state."""
        controls = {"enable": pb.SetWorkerStateRequest.ENABLE,
                    "disable": pb.SetWorkerStateRequest.DISABLE,
                    "drain": pb.SetWorkerStateRequest.DRAIN}
        if state not in controls:
            raise InvalidArgument(f"state {state!r}: expected one of enable, disable, drain")
        resp = self._unary("SetWorkerState",
                           pb.SetWorkerStateRequest(worker=name, control=controls[state]))
        return [Worker.from_proto(w) for w in resp.workers]

    def tasks(self, job_id: str) -> List[Task]:
        """The job's tasks: as the scheduler holds them now, or as recorded for an ended job."""
        resp = self._unary("ListTasks", pb.ListTasksRequest(job_id=job_id))
        return [Task.from_proto(t) for t in resp.tasks]

    def logs(self, job_id: str, *, task: Optional[int] = None, after_seq: int = 0,
             follow: bool = False, poll_seconds: float = 1.0) -> Iterator[LogLine]:
        """The lines workers logged running the job's tasks (or task ``task``'s), in the order
        the server took them, after ``after_seq``. With ``follow``, keeps polling until the job
        has ended and every line is read."""
        while True:
            req = pb.GetTaskLogsRequest(job_id=job_id, after_seq=after_seq)
            if task is not None:
                req.task_index = task
            resp = self._unary("GetTaskLogs", req)
            for line in resp.lines:
                yield LogLine.from_proto(line)
            after_seq = resp.next_seq
            if resp.lines:
                continue  # the next page at once
            if not follow or resp.job_ended:
                return
            time.sleep(poll_seconds)

    # --- watching ---
    def watch(self, job_id: str) -> Iterator[Progress]:
        """Follows the job: a :class:`Progress` now, then whenever it changes, the last one with
        a final state. Streams are renewed every minute, and an unreachable server is retried
        for ``retry_seconds``."""
        backoff = _Backoff(self.retry_seconds)
        req = pb.WatchJobRequest(job_id=job_id)
        while True:
            last: Optional[Job] = None
            stream = self._stub.WatchJob(req, timeout=WATCH_STREAM_SECONDS,
                                         metadata=self._metadata)
            try:
                for m in stream:
                    backoff.reset()
                    last = Job.from_proto(m)
                    yield Progress.of(last)
                    if last.state.final:
                        return
            except grpc.RpcError as e:
                if e.code() == grpc.StatusCode.DEADLINE_EXCEEDED:
                    continue
                err = self._error(e, "WatchJob")
                if isinstance(err, errors.Unavailable) and backoff.wait():
                    self._connect()
                    continue
                raise err from None
            finally:
                stream.cancel()  # a caller that stops iterating early ends the stream now
            if last is not None and last.state.final:
                return
            # The stream ended without a final state (a server going away): look again.
            if not backoff.wait():
                raise errors.Unavailable(f"watch {job_id}: the stream ended before the job did")

    def wait(self, job_id: str) -> Job:
        """Waits until the job ends and returns it (whatever its final state)."""
        last = None
        for progress in self.watch(job_id):
            last = progress
        assert last is not None
        return last.job

    # --- results ---
    def fetch(self, job_id: str, path: Union[str, os.PathLike], *, preview: bool = False,
              exposure: float = 0.0, tonemap: str = "clamp") -> str:
        """Writes the job's OpenEXR result to ``path`` (through ``path``.part, renamed when
        complete, so a failed fetch leaves no half file) and returns the path. A ``path`` ending
        in .png gets the 8-bit sRGB preview instead, as ``lightfarm fetch -o out.png`` makes it:
        radiance times 2^``exposure``, then the ``tonemap`` curve ("clamp" or "filmic").
        FailedPrecondition until the job has succeeded, unless ``preview`` asks for the tiles
        merged so far."""
        path = os.fspath(path)
        self._check_preview(path, exposure, tonemap)
        return self._fetch_one(pb.FetchResultRequest(job_id=job_id, preview=preview), path,
                               exposure, tonemap, f"job {job_id}")

    def fetch_frames(self, job_id: str, pattern: Union[str, os.PathLike], *,
                     frames: Union[None, str, Iterable[int]] = None, exposure: float = 0.0,
                     tonemap: str = "clamp") -> List[str]:
        """Writes a shot's finished frames as ``lightfarm fetch JOB -o out_####.exr`` does: each
        to ``pattern`` with its run of '#' replaced by the frame number (zero-padded to as many
        digits), an OpenEXR, or the PNG preview for a pattern ending in .png. ``frames`` ("A-B",
        "A-B:STEP", "N" or frame numbers) picks some, each one of the shot's; without it, every
        frame done so far (FailedPrecondition when there is none yet). Returns the paths written,
        in frame order. InvalidArgument for a still (use :meth:`fetch`), a frame not in the shot
        or a pattern that cannot number the frames."""
        pattern = os.fspath(pattern)
        self._check_preview(pattern, exposure, tonemap)
        job = self.get(job_id)
        if not job.params.HasField("shot"):
            raise InvalidArgument(f"job {job_id} is a still, not a shot: fetch() writes its image")
        s = job.params.shot
        shot = FrameRange(s.first, s.last, s.step or 1)
        if frames is None:
            wanted = [f.frame for f in job.proto.frames if f.done]
            if not wanted:
                raise errors.FailedPrecondition(
                    f"job {job_id} has no finished frame yet (0/{job.proto.frames_total})")
        else:
            wanted = list(parse_frames(frames) if isinstance(frames, str) else frames)
            for frame in wanted:
                if frame not in shot:
                    raise InvalidArgument(f"frames: frame {frame} is not one of job {job_id}'s "
                                          f"({shot})")
        named = (FrameRange(wanted[0], wanted[0]) if len(wanted) == 1
                 else FrameRange(min(wanted), max(wanted)))
        check_frame_pattern("pattern", pattern, named)
        return [self._fetch_one(pb.FetchResultRequest(job_id=job_id, frame=frame),
                                frame_path(pattern, frame), exposure, tonemap,
                                f"job {job_id} frame {frame}")
                for frame in sorted(set(wanted))]

    @staticmethod
    def _check_preview(path: str, exposure: float, tonemap: str) -> None:
        png = path.lower().endswith(".png")
        if not png and (exposure != 0.0 or tonemap != "clamp"):
            raise InvalidArgument(f"{path}: exposure and tonemap make the PNG preview; give a "
                                  "path ending in .png")
        if png and tonemap not in TONEMAPS:
            raise InvalidArgument(f"tonemap {tonemap!r}: expected clamp or filmic")

    def _fetch_one(self, req: pb.FetchResultRequest, path: str, exposure: float, tonemap: str,
                   what: str) -> str:
        """Streams one result to ``path``.part, made a PNG for a .png path, then renamed."""
        temp = path + ".part"
        try:
            with open(temp, "wb") as f:
                for chunk in self._stub.FetchResult(req, timeout=FETCH_SECONDS,
                                                    metadata=self._metadata):
                    f.write(chunk.data)
            if path.lower().endswith(".png"):
                with open(temp, "rb") as f:
                    image = exr_to_png(f.read(), exposure=exposure, tonemap=tonemap, what=what)
                with open(temp, "wb") as f:
                    f.write(image)
        except grpc.RpcError as e:
            _remove(temp)
            raise self._error(e, "FetchResult") from None
        except BaseException:
            _remove(temp)
            raise
        os.replace(temp, path)
        return path

    # --- submitting ---
    def submit(self, scene_path: Union[str, os.PathLike], *, spp: Optional[int] = None,
               seed: int = 0,
               max_depth: int = -1, tile: int = 32, passes: int = 1, method: str = "path",
               priority: int = 0, name: Optional[str] = None, camera: str = "",
               resolution: Optional[Tuple[int, int]] = None, clamp: float = 0.0,
               aovs: Union[int, Sequence[str]] = 0, filter: Optional[str] = None,
               filter_width: Optional[float] = None, sampler: str = "sobol",
               light_sampling: str = "bvh", target_error: float = 0.0,
               time_limit: float = 0.0, max_spp: int = 1 << 16, noise_threshold: float = 0.0,
               patches: int = 4000, patch_size: float = 0.0, solver: str = "jacobi",
               tolerance: float = 1e-4, max_iterations: int = 10000, display: str = "smooth",
               sweep_tasks: int = 8, max_patches: int = 0, radiosity: str = "flat",
               link_error: float = 1e-4,
               photons_per_pass: int = 1 << 18, initial_radius: float = 0.0,
               alpha: float = 2.0 / 3.0, frames: Optional[str] = None,
               frame: Optional[int] = None, fps: Optional[float] = None, shutter: float = 0.0,
               chunk: Optional[int] = None, request_id: Optional[str] = None,
               tags: Sequence[str] = (), max_workers: int = 0,
               max_attempts: int = 3, blocklist_after: int = 3,
               after: Sequence[str] = ()) -> str:
        """Uploads the scene and every file it names (those the server lacks, resuming a broken
        upload) and queues it as a job; returns the job id.

        The settings and their defaults are ``lightfarm submit``'s: ``spp``, ``seed``,
        ``max_depth`` (-1 unlimited), ``tile``, ``passes``, ``method`` (path, radiosity,
        whitted, light, bdpt, ppm), ``priority`` (higher runs first), ``name`` (default the
        scene file's name), ``camera`` (a glTF camera's name), ``resolution`` (width, height),
        ``clamp``, ``aovs`` (flags or names: "albedo", "normal", "depth", "illuminance"), ``filter`` ("box",
        "gaussian", "blackman-harris") and ``filter_width``, ``sampler`` ("sobol",
        "independent"), ``light_sampling`` ("bvh", "power"); adaptive sampling with
        ``target_error``, ``time_limit`` (seconds) and ``max_spp``, or per pixel with
        ``noise_threshold`` (Cycles' Noise Threshold; ``spp`` is then each pixel's minimum,
        by default Cycles' automatic one, ceil(16 / threshold^0.3), as the CLI's); radiosity's ``patches``,
        ``patch_size``, ``solver``, ``tolerance``, ``max_iterations``, ``display``,
        ``sweep_tasks``, ``max_patches``, ``radiosity`` ("flat" or "hierarchical") and
        ``link_error``; photon mapping's ``photons_per_pass``,
        ``initial_radius``, ``alpha``. A shot of an animated scene: ``frames`` ("A-B",
        "A-B:STEP") or ``frame`` (N alone), frame f showing the scene at f / ``fps`` seconds
        (default 24), ``shutter`` (motion blur: frames the shutter stays open, centred on each
        frame; 0 the instant) and ``chunk`` (whole frames a task, default 1). ``tags`` (only
        workers having every one take the job) and ``max_workers`` (at most this many workers
        at once, 0 no cap); ``max_attempts`` (failures of one task that fail the job) and
        ``blocklist_after`` (a worker's failures in the job after which it gets none of its
        tasks), 1 to 100. ``after``: job ids; the job leases nothing until each has succeeded,
        and fails when one fails or is cancelled (NotFound for an unknown id,
        FailedPrecondition for one that failed or was cancelled). The server checks them all and the scene (InvalidArgument
        with the loader's message). ``request_id`` makes retries idempotent (default: 128
        random bits, the same on every retry of this call).
        """
        scene_path = os.fspath(scene_path)
        if spp is None:
            spp = _noise_threshold_min_spp(noise_threshold) if noise_threshold > 0 else 16
        if isinstance(tags, str):  # a str is a sequence of one-letter tags
            raise InvalidArgument(f"tags {tags!r}: a list of tags, e.g. [{tags!r}]")
        if isinstance(after, str):  # a str is a sequence of one-letter ids
            raise InvalidArgument(f"after {after!r}: a list of job ids, e.g. [{after!r}]")
        if method not in METHODS:
            raise InvalidArgument(f"method {method!r}: expected one of {', '.join(METHODS)}")
        text, named = scene_files(scene_path)
        scene_name = os.path.basename(scene_path)
        check_scene_path(scene_name)
        contents: Dict[str, bytes] = {}

        def ref(path: str, data: bytes) -> common_pb2.SceneFile:
            digest = hashlib.sha256(data).hexdigest()
            contents[digest] = data
            return common_pb2.SceneFile(path=path, hash=digest, size=len(data))

        params = common_pb2.RenderParams(
            spp=spp, seed=seed, max_depth=max_depth, tile=tile, passes=passes, method=method,
            target_error=target_error, time_limit_seconds=time_limit, max_spp=max_spp,
            noise_threshold=noise_threshold,
            camera=camera, clamp=clamp, aovs=_aov_flags(aovs), sampler=_choice(
                "sampler", sampler, _SAMPLERS),
            light_strategy=_choice("light_sampling", light_sampling, _LIGHT_SAMPLING))
        if resolution is not None:
            params.width, params.height = int(resolution[0]), int(resolution[1])
        if filter is not None:
            params.filter_type = _choice("filter", filter, _FILTERS)
            params.filter_width = (filter_width if filter_width is not None
                                   else 1.0 if filter == "box" else 3.0)
        if method == "radiosity":
            params.radiosity.CopyFrom(common_pb2.RadiosityParams(
                patches=patches, patch_size=patch_size, solver=solver, tolerance=tolerance,
                max_iterations=max_iterations, display=display, sweep_tasks=sweep_tasks,
                max_patches=max_patches, form=radiosity, link_error=link_error))
        shot = _shot_params(frames, frame, fps, shutter, chunk)
        if shot is not None:
            params.shot.CopyFrom(shot)
        if method == "ppm":
            params.ppm.CopyFrom(common_pb2.PhotonParams(
                photons_per_pass=photons_per_pass, initial_radius=initial_radius, alpha=alpha))
        req = pb.SubmitJobRequest(
            scene=ref(scene_name, text), files=[ref(n, d) for n, d in named], params=params,
            priority=priority, name=name or scene_name,
            request_id=request_id or secrets.token_hex(16), tags=list(tags),
            max_workers=max_workers, max_attempts=max_attempts, blocklist_after=blocklist_after,
            after=list(after))
        files = [req.scene] + list(req.files)

        backoff = _Backoff(self.retry_seconds)
        while True:
            try:
                return self._submit_once(req, files, contents)
            except (errors.Unavailable, errors.Aborted):
                # Aborted: another client was uploading one of the blobs; the retry resumes
                # from its bytes, or finds the blob stored.
                if not backoff.wait():
                    raise
                self._connect()

    def _submit_once(self, req: pb.SubmitJobRequest, files: List[common_pb2.SceneFile],
                     contents: Dict[str, bytes]) -> str:
        missing = self._unary("MissingBlobs", pb.MissingBlobsRequest(hashes=sorted(contents)))
        by_hash = {f.hash: f for f in files}
        for digest in missing.hashes:
            if digest in by_hash:
                self._upload(by_hash[digest], contents[digest])
        return self._unary("SubmitJob", req, timeout=SUBMIT_SECONDS).job_id

    def _upload(self, file: common_pb2.SceneFile, data: bytes) -> None:
        """Sends what the server lacks of one blob, from where its bytes end."""
        offset = 0
        try:
            held = self._stub.BlobUploadOffset(
                pb.BlobUploadOffsetRequest(hash=file.hash, size=file.size),
                timeout=UNARY_SECONDS, metadata=self._metadata)
            offset = min(held.offset, len(data))
        except grpc.RpcError as e:
            # A server of an earlier version, without the call, takes whole uploads only.
            if e.code() != grpc.StatusCode.UNIMPLEMENTED:
                raise self._upload_error(file, e) from None
        if offset == len(data):
            return

        def chunks() -> Iterator[pb.UploadBlobRequest]:
            at = offset
            first = True
            while first or at < len(data):
                part = data[at:at + CHUNK_BYTES]
                if first:
                    yield pb.UploadBlobRequest(hash=file.hash, size=file.size, offset=offset,
                                               data=part)
                    first = False
                else:
                    yield pb.UploadBlobRequest(data=part)
                at += len(part)

        try:
            self._stub.UploadBlob(chunks(), timeout=UPLOAD_SECONDS, metadata=self._metadata)
        except grpc.RpcError as e:
            raise self._upload_error(file, e) from None

    def _upload_error(self, file: common_pb2.SceneFile, e: grpc.RpcError) -> LightfarmError:
        err = self._error(e, "UploadBlob")
        return type(err)(f"{file.path}: upload: {err.message}", err.code)


def _noise_threshold_min_spp(threshold: float) -> int:
    """Cycles' automatic minimum for a noise threshold, at least 4, even: as
    lf::NoiseThresholdMinSpp (job/src/adaptive_plan.cc)."""
    n = max(4, math.ceil(16 / threshold ** 0.3))
    return n + (n & 1)


def _remove(path: str) -> None:
    try:
        os.remove(path)
    except OSError:
        pass


def _shot_params(frames: Optional[str], frame: Optional[int], fps: Optional[float],
                 shutter: float, chunk: Optional[int]) -> Optional[common_pb2.ShotParams]:
    """The shot of submit's arguments, checked as ``lightfarm submit --frames`` checks them;
    None for a still."""
    if frames is not None and frame is not None:
        raise InvalidArgument(f"frame {frame} with frames {frames!r}: give one frame or a range, "
                              "not both")
    if frames is None and frame is None:
        for what, value in (("fps", fps), ("chunk", chunk)):
            if value is not None:
                raise InvalidArgument(f"{what} {value}: applies to frames or frame; a still has "
                                      "no time")
        if shutter != 0:
            raise InvalidArgument(f"shutter {shutter}: motion blur needs frames or frame; a still "
                                  "has no time")
        return None
    if frames is not None:
        if not isinstance(frames, str):
            raise InvalidArgument(f"frames {frames!r}: expected a string A-B[:STEP]")
        span = parse_frames(frames)
    else:
        if isinstance(frame, bool) or not isinstance(frame, int):
            raise InvalidArgument(f"frame {frame!r}: expected a whole frame number")
        span = check_range(FrameRange(frame, frame))
    fps = DEFAULT_FPS if fps is None else float(fps)
    chunk = 1 if chunk is None else chunk
    if not MIN_FPS <= fps <= MAX_FPS:
        raise InvalidArgument(f"fps {fps}: expected {MIN_FPS} to {MAX_FPS:g}")
    if not 0 <= shutter <= MAX_SHUTTER:
        raise InvalidArgument(f"shutter {shutter}: expected 0 (the instant) to {MAX_SHUTTER:g} "
                              "frames")
    if isinstance(chunk, bool) or not isinstance(chunk, int) or not 1 <= chunk <= MAX_CHUNK:
        raise InvalidArgument(f"chunk {chunk}: expected 1 to {MAX_CHUNK} frames a task")
    return common_pb2.ShotParams(first=span.first, last=span.last, step=span.step, fps=fps,
                                 shutter=shutter, chunk=chunk)


def _choice(what: str, value: str, choices: Dict[str, int]) -> int:
    if value not in choices:
        raise InvalidArgument(f"{what} {value!r}: expected one of {', '.join(choices)}")
    return choices[value]


def _aov_flags(aovs: Union[int, Iterable[str]]) -> int:
    if isinstance(aovs, int):
        return aovs
    if isinstance(aovs, str):
        aovs = [a for a in aovs.split(",") if a]
    flags = 0
    for a in aovs:
        flags |= _choice("aov", a, _AOVS)
    return flags
