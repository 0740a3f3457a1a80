"""A real Flamenco farm on localhost for the tests: a Manager with the
add-on's job type in its `scripts/`, Workers that run `farm_blender.py` as
their `blender`, and shared storage in a temporary folder, all bound to
127.0.0.1. The binaries come from CAUSTIC_FLAMENCO, by default the
project's `../shared/flamenco/` (its README says how they were built).
"""

import base64
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
FLAMENCO = Path(os.environ.get("CAUSTIC_FLAMENCO", REPO.parent / "shared" / "flamenco"))
JOB_TYPE = REPO / "examples" / "flamenco" / "caustics.js"
WINDOWS_STORAGE = "S:\\farm"


def missing() -> str | None:
    """Why the farm cannot run here, or None."""
    for binary in ("flamenco-manager", "flamenco-worker"):
        if not os.access(FLAMENCO / binary, os.X_OK):
            return f"no Flamenco {binary} in {FLAMENCO} (set CAUSTIC_FLAMENCO to the folder of its binaries)"
    return None


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Farm:
    """A Manager and `workers` Workers under `root`; `shared` is the shared storage."""

    def __init__(self, root: Path, workers: int = 2):
        self.root, self.shared = root, root / "shared"
        self.url = f"http://127.0.0.1:{_free_port()}"
        manager = root / "manager"
        (manager / "scripts").mkdir(parents=True)
        self.shared.mkdir()
        # the Manager reads job types from scripts/ beside its real path, so it is copied, not linked
        shutil.copy(FLAMENCO / "flamenco-manager", manager)
        shutil.copy(JOB_TYPE, manager / "scripts")
        blender = root / "blender"
        blender.write_text(f"#!/bin/sh\nexec {sys.executable!r} {str(HERE / 'farm_blender.py')!r} \"$@\"\n")
        blender.chmod(0o755)
        (manager / "flamenco-manager.yaml").write_text(json.dumps({
            "_meta": {"version": 3}, "manager_name": "test farm",
            "database": str(manager / "flamenco-manager.sqlite"), "listen": self.url.removeprefix("http://"),
            "autodiscoverable": False, "local_manager_storage_path": str(manager / "storage"),
            "shared_storage_path": str(self.shared), "shaman": {"enabled": False},
            "task_timeout": "10m0s", "worker_timeout": "1m0s",
            "variables": {"blender": {"values": [{"platform": "linux", "value": str(blender)}]},
                          "blenderArgs": {"values": [{"platform": "all", "value": "-b -y"}]},
                          # shared storage as each platform's Workers mount it
                          "storage": {"is_twoway": True, "values": [
                              {"platform": "linux", "value": str(self.shared)},
                              {"platform": "windows", "value": WINDOWS_STORAGE}]}},
        }))
        self.processes = {"manager": self._start("manager", [str(manager / "flamenco-manager")], manager)}
        self._wait_for_manager()
        for n in range(1, workers + 1):
            self.start_worker(f"worker-{n}")

    def _start(self, name: str, command: list[str], folder: Path, env: dict | None = None) -> subprocess.Popen:
        log = open(self.root / f"{name}.log", "ab")
        return subprocess.Popen(command, cwd=folder, stdout=log, stderr=subprocess.STDOUT, env=env,
                                start_new_session=True)

    def start_worker(self, name: str) -> None:
        folder = self.root / name
        (folder / "home").mkdir(parents=True, exist_ok=True)
        (folder / "flamenco-worker.yaml").write_text(json.dumps({
            "manager_url": self.url, "worker_name": name, "task_types": ["blender", "misc", "file-management"]}))
        self.processes[name] = self._start(name, [str(FLAMENCO / "flamenco-worker"), "-manager", self.url], folder,
                                           dict(os.environ, FLAMENCO_HOME=str(folder / "home")))

    def stop(self, name: str, sig: int = signal.SIGINT) -> None:
        process = self.processes.pop(name)
        os.killpg(process.pid, sig)
        try:
            process.wait(30)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()

    def close(self) -> None:
        for name in [n for n in self.processes if n != "manager"] + ["manager"]:
            self.stop(name)

    def _wait_for_manager(self) -> None:
        deadline = time.monotonic() + 30
        while True:
            try:
                self.get("/api/v3/version")
                return
            except (urllib.error.URLError, ConnectionError):
                if time.monotonic() > deadline:
                    raise RuntimeError(f"the Flamenco Manager did not start: {self.log('manager')[-2000:]}")
                time.sleep(0.2)

    def log(self, name: str) -> str:
        return (self.root / f"{name}.log").read_text(errors="replace")

    def request(self, method: str, path: str, body: dict | None = None, user: tuple[str, str] | None = None):
        """(status, the answer: parsed JSON, text, or None); as Worker `user` (id, secret) where given."""
        data = None if body is None else json.dumps(body).encode()
        headers = {"Content-Type": "application/json"}
        if user is not None:
            headers["Authorization"] = "Basic " + base64.b64encode(":".join(user).encode()).decode()
        request = urllib.request.Request(self.url + path, data=data, method=method, headers=headers)
        try:
            with urllib.request.urlopen(request, timeout=30) as answer:
                status, raw, kind = answer.status, answer.read(), answer.headers.get("Content-Type", "")
        except urllib.error.HTTPError as error:
            status, raw, kind = error.code, error.read(), error.headers.get("Content-Type", "")
        if not raw:
            return status, None
        return status, json.loads(raw) if "json" in kind else raw.decode(errors="replace")

    def get(self, path: str):
        status, answer = self.request("GET", path)
        if status != 200:
            raise ConnectionError(f"GET {path}: {status} {answer}")
        return answer

    def job(self, settings: dict, name: str = "caustics") -> dict:
        """The job of the add-on's type with `settings`, as submitted."""
        return {"name": name, "type": "caustics", "priority": 50, "submitter_platform": "linux",
                "settings": settings, "metadata": {}}

    def submit(self, settings: dict, name: str = "caustics") -> str:
        """Submit the job once every running Worker asks for work
        (`awake`): one that has not yet signed on would leave its share of
        the chunks to the others."""
        self.awake()
        status, answer = self.request("POST", "/api/v3/jobs", self.job(settings, name))
        if status != 200:
            raise AssertionError(f"the Manager refused the job: {status} {answer}")
        return answer["id"]

    def awake(self, timeout: float = 60) -> None:
        """Wait until the Manager lists each running Worker as awake."""
        running = {name for name in self.processes if name != "manager"}
        deadline = time.monotonic() + timeout
        while True:
            workers = self.get("/api/v3/worker-mgt/workers")["workers"]
            if running <= {worker["name"] for worker in workers if worker["status"] == "awake"}:
                return
            if time.monotonic() > deadline:
                raise TimeoutError(f"Workers {sorted(running)} not all awake after {timeout} s: {workers}")
            time.sleep(0.2)

    def check(self, settings: dict):
        """(status, message) of POST /jobs/check: 204 when the job compiles."""
        return self.request("POST", "/api/v3/jobs/check", self.job(settings))

    def wait(self, job_id: str, timeout: float = 600, until=("completed", "failed", "canceled")) -> str:
        deadline = time.monotonic() + timeout
        while True:
            status = self.get(f"/api/v3/jobs/{job_id}")["status"]
            if status in until:
                return status
            if time.monotonic() > deadline:
                raise TimeoutError(f"job {job_id} still {status} after {timeout} s")
            time.sleep(0.5)

    def task_for(self, platform: str) -> dict | None:
        """The task the Manager hands a Worker of `platform`, its variables
        expanded for it, asked through the Workers' API by one that
        registers, takes a task and signs off again (the Manager queues
        the task anew); None when there is none."""
        name = f"{platform}-worker"
        status, worker = self.request("POST", "/api/v3/worker/register-worker", {
            "secret": "farm", "platform": platform, "supported_task_types": ["blender"], "name": name})
        assert status == 200, worker
        user = (worker["uuid"], "farm")
        for path, body in (("/api/v3/worker/sign-on", {"name": name, "supported_task_types": ["blender"],
                                                        "software_version": "3.8.5"}),
                           ("/api/v3/worker/state-changed", {"status": "awake"})):
            status, answer = self.request("POST", path, body, user)
            assert status in (200, 204), (path, status, answer)
        status, task = self.request("POST", "/api/v3/worker/task", None, user)
        self.request("POST", "/api/v3/worker/sign-off", None, user)
        return task if status == 200 else None

    def tasks(self, job_id: str) -> list[dict]:
        return self.get(f"/api/v3/jobs/{job_id}/tasks")["tasks"]

    def task_log(self, task_id: str) -> str:
        """The task's whole log, as the Manager serves it."""
        info = self.get(f"/api/v3/tasks/{task_id}/log")
        if not info:
            return ""
        with urllib.request.urlopen(self.url + info["url"], timeout=30) as answer:
            return answer.read().decode(errors="replace")
