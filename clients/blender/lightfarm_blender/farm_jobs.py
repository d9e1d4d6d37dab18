"""The add-on's talks with the farm, on a background thread each so Blender's UI never waits
on the network: submit (upload, SubmitJob, then watch the job) and fetch. Never imports bpy:
the operators copy a FarmTask's status into the scene from a timer."""

from __future__ import annotations

import dataclasses
import os
import shutil
import threading
from typing import Any, Callable, Dict, List, Optional

import lightfarm


@dataclasses.dataclass(frozen=True)
class Connection:
    """The panel's farm settings: the address, a token file and a TLS CA (absolute, or None
    for the environment's LIGHTFARM_TOKEN / LIGHTFARM_TLS_CA)."""
    server: str
    token_file: Optional[str]
    tls_ca: Optional[str]

    def client(self) -> lightfarm.Client:
        return lightfarm.Client(self.server or None, token_file=self.token_file,
                                tls_ca=self.tls_ca)


class FarmTask:
    """One piece of work on its own thread; ``status`` is read from Blender's main thread."""

    def __init__(self, what: str, work: Callable[["FarmTask"], None]) -> None:
        self.what = what
        self._lock = threading.Lock()
        self._status: Dict[str, Any] = {"message": f"{what}…", "done": False, "error": ""}
        self._thread = threading.Thread(target=self._run, args=(work,), daemon=True,
                                        name=f"lightfarm {what}")
        self._thread.start()

    def _run(self, work: Callable[["FarmTask"], None]) -> None:
        try:
            work(self)
        except lightfarm.LightfarmError as e:
            self.update(error=f"{self.what}: {e.code.name}: {e.message}")
        except Exception as e:  # the panel shows it: a thread's traceback reaches no one
            self.update(error=f"{self.what}: {type(e).__name__}: {e}")
        finally:
            self.update(done=True)

    def update(self, **values: Any) -> None:
        with self._lock:
            self._status.update(values)

    @property
    def status(self) -> Dict[str, Any]:
        with self._lock:
            return dict(self._status)

    def join(self, timeout: Optional[float] = None) -> bool:
        """Waits for the work to end (the headless test does; the UI polls instead)."""
        self._thread.join(timeout)
        return not self._thread.is_alive()


def submit(conn: Connection, scene_file: str, settings: Dict[str, Any],
           remove_dir: Optional[str]) -> FarmTask:
    """Uploads and submits ``scene_file`` with ``settings`` (Client.submit's arguments), then
    follows the job until it ends; ``remove_dir`` (the temporary export) goes once uploaded."""

    def work(task: FarmTask) -> None:
        def remove_export() -> None:
            if remove_dir:
                shutil.rmtree(remove_dir, ignore_errors=True)

        try:
            farm = conn.client()  # a token file that cannot be read fails here
        except BaseException:
            remove_export()
            raise
        with farm:
            try:
                job_id = farm.submit(scene_file, **settings)
            finally:
                remove_export()
            task.update(job_id=job_id, message=f"job {job_id} submitted")
            for p in farm.watch(job_id):
                frames = p.job.proto
                task.update(state=p.state.name, fraction=p.fraction,
                            message=(f"job {job_id} {p.state.name.lower()}: "
                                     f"{frames.frames_done}/{frames.frames_total} frames, "
                                     f"{p.tasks_done}/{p.tasks_total} tasks"))
            if p.state != lightfarm.JobState.SUCCEEDED:
                task.update(error=f"job {job_id} {p.state.name.lower()}: {p.error}")

    return FarmTask("submit", work)


def fetch(conn: Connection, job_id: str, pattern: str) -> FarmTask:
    """Writes the job's finished frames to ``pattern`` (its '#' the frame number)."""

    def work(task: FarmTask) -> None:
        os.makedirs(os.path.dirname(pattern) or ".", exist_ok=True)
        with conn.client() as farm:
            paths: List[str] = farm.fetch_frames(job_id, pattern)
        task.update(paths=paths, message=f"job {job_id}: {len(paths)} frames written "
                                         f"({os.path.dirname(pattern)})")

    return FarmTask("fetch", work)
