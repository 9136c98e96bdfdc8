"""Fixtures for the viz tests: small objects, synthetic grasp rows, a headless Chromium.

The browser is driven through the DevTools protocol over pipes (``--remote-debugging-pipe``:
JSON messages separated by NUL bytes on file descriptors 3 and 4), so no extra Python
package is needed. Tests that need it skip when no Chromium is installed.
"""

from __future__ import annotations

import json
import os
import queue
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import trimesh

from affordgrasp.hands import get_hand
from affordgrasp.objects import load_object

CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")


def find_chromium() -> str | None:
    override = os.environ.get("AFFORDGRASP_CHROMIUM")
    if override:
        return override if Path(override).exists() else None
    for name in CHROMIUM_NAMES:
        path = shutil.which(name)
        if path:
            return path
    return None


# Moves the two pipe ends (argv 1 and 2) to fds 3 and 4 and execs the rest of argv. Both
# ends are first copied above fd 4 (a pipe may itself be fd 3 or 4), as copies closed on exec,
# so that only fds 3 and 4 reach the browser.
_WIRE_PIPES = """
import fcntl, os, sys
ends = [int(a) for a in sys.argv[1:3]]
moved = [fcntl.fcntl(fd, fcntl.F_DUPFD_CLOEXEC, 5) for fd in ends]
for fd in ends:
    os.close(fd)
os.dup2(moved[0], 3)
os.dup2(moved[1], 4)
os.execv(sys.argv[3], sys.argv[3:])
"""


class Browser:
    """A headless Chromium page driven over the DevTools protocol."""

    def __init__(self, executable: str, width: int = 1200, height: int = 800):
        self._profile = tempfile.mkdtemp(prefix="affordgrasp-chromium-")
        to_child_r, self._to_child = os.pipe()
        self._from_child, from_child_w = os.pipe()

        args = [
            executable,
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            # WebGL without a GPU: SwiftShader through ANGLE (software, deterministic).
            "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader",
            "--disable-quic",
            "--no-first-run",
            "--no-default-browser-check",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--disable-extensions",
            "--mute-audio",
            f"--window-size={width},{height}",
            f"--user-data-dir={self._profile}",
            "--remote-debugging-pipe",
            "about:blank",
        ]
        # The protocol reads fd 3 and writes fd 4: a short launcher moves the pipes there
        # and execs the browser (preexec_fn could, but it runs Python between fork and exec,
        # which can deadlock when this process has other threads, as it does).
        self.proc = subprocess.Popen(
            [sys.executable, "-c", _WIRE_PIPES, str(to_child_r), str(from_child_w), *args],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            pass_fds=(to_child_r, from_child_w),
        )
        os.close(to_child_r)
        os.close(from_child_w)
        self._next_id = 0
        self._replies: dict[int, dict] = {}
        self._events: queue.Queue = queue.Queue()
        self._lock = threading.Condition()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()
        self.console_errors: list[str] = []
        target = self.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        self.session = self.call("Target.attachToTarget", {"targetId": target, "flatten": True})[
            "sessionId"
        ]
        for domain in ("Runtime", "Log", "Page"):
            self.call(f"{domain}.enable", session=True)

    def _read(self) -> None:
        buffer = b""
        while True:
            chunk = os.read(self._from_child, 1 << 16)
            if not chunk:
                with self._lock:
                    self._lock.notify_all()
                return
            buffer += chunk
            while b"\0" in buffer:
                raw, buffer = buffer.split(b"\0", 1)
                message = json.loads(raw)
                if "id" in message:
                    with self._lock:
                        self._replies[message["id"]] = message
                        self._lock.notify_all()
                else:
                    self._events.put(message)

    def call(
        self,
        method: str,
        params: dict | None = None,
        *,
        session: bool = False,
        timeout: float = 30.0,
    ):
        self._next_id += 1
        message = {"id": self._next_id, "method": method, "params": params or {}}
        if session:
            message["sessionId"] = self.session
        os.write(self._to_child, json.dumps(message).encode() + b"\0")
        deadline = time.monotonic() + timeout
        with self._lock:
            while self._next_id not in self._replies:
                left = deadline - time.monotonic()
                if left <= 0 or self.proc.poll() is not None:
                    raise TimeoutError(f"no reply from Chromium to {method}")
                self._lock.wait(min(left, 0.5))
            reply = self._replies.pop(self._next_id)
        if "error" in reply:
            raise RuntimeError(f"{method}: {reply['error']}")
        return reply.get("result", {})

    def collect_events(self) -> None:
        """Move console errors and uncaught exceptions seen so far into ``console_errors``."""
        while True:
            try:
                event = self._events.get_nowait()
            except queue.Empty:
                return
            method, params = event.get("method"), event.get("params", {})
            if method == "Runtime.exceptionThrown":
                details = params.get("exceptionDetails", {})
                text = details.get("exception", {}).get("description") or details.get("text")
                self.console_errors.append(f"uncaught: {text}")
            elif method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert"):
                args = [a.get("value", a.get("description", "")) for a in params.get("args", [])]
                self.console_errors.append("console.error: " + " ".join(map(str, args)))
            elif method == "Log.entryAdded" and params.get("entry", {}).get("level") == "error":
                entry = params["entry"]
                self.console_errors.append(f"log ({entry.get('source')}): {entry.get('text')}")

    def navigate(self, url: str) -> None:
        self.call("Page.navigate", {"url": url}, session=True)

    def evaluate(self, expression: str):
        result = self.call(
            "Runtime.evaluate", {"expression": expression, "returnByValue": True}, session=True
        )
        return result.get("result", {}).get("value")

    def wait_for(self, expression: str, timeout: float = 30.0):
        """Poll a JavaScript expression until it is truthy; returns its value (or the last)."""
        deadline = time.monotonic() + timeout
        value = None
        while time.monotonic() < deadline:
            value = self.evaluate(expression)
            if value:
                return value
            time.sleep(0.1)
        return value

    def screenshot(self) -> np.ndarray:
        import base64
        import io

        from PIL import Image

        data = self.call("Page.captureScreenshot", {"format": "png"}, session=True)["data"]
        return np.asarray(Image.open(io.BytesIO(base64.b64decode(data))).convert("RGB"))

    def close(self) -> None:
        try:
            self.call("Browser.close", timeout=5.0)
        except Exception:  # noqa: BLE001 - closing anyway
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        os.close(self._to_child)
        os.close(self._from_child)
        shutil.rmtree(self._profile, ignore_errors=True)


@pytest.fixture(scope="session")
def chromium():
    executable = find_chromium()
    if executable is None:
        override = os.environ.get("AFFORDGRASP_CHROMIUM")
        reason = (
            f"AFFORDGRASP_CHROMIUM={override} does not exist"
            if override
            else "Chromium is not installed (looked for: " + ", ".join(CHROMIUM_NAMES) + ")"
        )
        reason += (
            "; install Debian's 'chromium' package (apt-get install chromium) or set "
            "AFFORDGRASP_CHROMIUM to run the browser tests"
        )
        if os.environ.get("AFFORDGRASP_REQUIRE_BROWSER") == "1":
            pytest.fail(reason + " (AFFORDGRASP_REQUIRE_BROWSER=1 forbids skipping)")
        pytest.skip(reason)
    browser = Browser(executable)
    try:
        yield browser
    finally:
        browser.close()


# --------------------------------------------------------------------------- objects, rows


@pytest.fixture(scope="session")
def box_object(tmp_path_factory):
    """A 20 x 4 x 3 cm box, as a mesh file object (no procedural family needed)."""
    path = tmp_path_factory.mktemp("objects") / "bar.stl"
    trimesh.creation.box((0.20, 0.04, 0.03)).export(path)
    return load_object(str(path))


def grasp_row_on_box(obj, *, spread: float = 0.0, closed: float = 0.6, sample: int = 0) -> dict:
    """A hand-made grasp row on ``box_object``: the palm 6 cm above the top face, approaching
    along -z of the object, fingers half closed; contacts on the top and side faces."""
    hand = get_hand("barrett")
    joints = hand.open_dofs(spread)
    for i, name in enumerate(hand.dof_names):
        if name.endswith("_prox"):
            joints[i] = closed
        elif name.endswith("_dist"):
            joints[i] = closed / 3.0
    pose = np.eye(4)
    pose[:3, :3] = np.diag([1.0, -1.0, -1.0])  # hand +z (approach) along object -z
    top = obj.mesh.bounds[1][2]
    pose[:3, 3] = [0.0, 0.0, top + 0.06]
    return {
        "object": obj.name,
        "object_hash": obj.mesh_hash,
        "hand": "barrett",
        "sample": sample,
        "seed": 0,
        "status": "grasped",
        "hand_pose": pose.reshape(-1).tolist(),
        "joints": joints.tolist(),
        "contact_points": [[0.0, 0.02, 0.0], [0.0, -0.02, 0.0], [0.05, 0.0, top]],
        "contact_normals": [[0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]],
        "contact_mu": [0.4, 0.4, 0.3],
        "contact_link": ["f1_dist", "f3_dist", "palm"],
        "use_point": [0.1, 0.0, 0.0],
        "use_normal": [1.0, 0.0, 0.0],
        "wrist_point": pose[:3, 3].tolist(),
        "wrist_axis": pose[:3, 2].tolist(),
    }


@pytest.fixture()
def box_row(box_object):
    return grasp_row_on_box(box_object)


def metric_row(rng: np.random.Generator, *, blunt: bool = True) -> dict:
    """Plausible metric values for a grasp row: pick finite, and beat (a blunt use point) or
    cut (a sharp one) finite, the hand well off the use point on a thick part."""
    wedge = rng.uniform(2.5, 3.1) if blunt else rng.uniform(0.4, 0.9)  # rad: 135° / 55° tests
    row = {
        "use_wedge_angle": float(wedge),
        "use_wedge_angle_fine": float(wedge),
        "use_edge_span": float(rng.uniform(0.31, 0.4)),
        "use_edge_thickness": float(rng.uniform(0.0, 0.0005)),
        "use_clearance": float(rng.uniform(0.04, 0.1)),
        "use_lever_ratio": float(rng.uniform(1.1, 1.9)),
        "contact_thickness": float(rng.uniform(0.01, 0.03)),
        "contact_width": float(rng.uniform(0.01, 0.03)),
        "epsilon": float(rng.uniform(0.31, 0.6)),
        "gws_volume": float(rng.uniform(0.0, 1e-3)),
        "epsilon_reason": "",
        "inertia": float(rng.uniform(1e-5, 1e-3)),
        **{
            f"hold_effort_{s}": float(rng.uniform(1.0, 50.0))
            for s in ("px", "nx", "py", "ny", "pz", "nz")
        },
        "impact_effort": float(rng.uniform(0.5, 20.0)),
        "discharge": float(rng.uniform(0.96, 1.0)),
        "use_force": float(rng.uniform(0.1, 5.0)),
        "use_edge": float(rng.uniform(4e4, 1e5)),
        "use_edge_angle": float(rng.uniform(0.2, 0.5)),
        "contact_reach": float(rng.uniform(-0.1, -0.01)),
    }
    row["epsilon_hand"] = row["epsilon"]  # objects within 0.25 m
    # a deep, flat striking surface when blunt; an edge has little behind it
    row["use_depth"] = 0.08 if blunt else 0.002
    row["use_relief"] = 1e-4 if blunt else 2e-3
    row["use_swing_cosine"] = 0.99
    return row


def write_dataset(directory: Path, objects: list, rows_per_object: int = 6, seed: int = 0) -> Path:
    """A small dataset directory: one Parquet shard per object (conventions: Sample columns),
    hand-made grasps (the hand rotated about the approach) and random plausible metrics;
    a few rows per object are failures (+inf efforts, ε = 0)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    from affordgrasp.schema import SCHEMA

    rng = np.random.default_rng(seed)
    directory.mkdir(parents=True, exist_ok=True)
    for k, obj in enumerate(objects):
        rows = []
        for i in range(rows_per_object):
            row = grasp_row_on_box(obj, spread=i / rows_per_object, sample=i)
            pose = np.asarray(row["hand_pose"]).reshape(4, 4)
            angle = 0.4 * i
            c, s = np.cos(angle), np.sin(angle)
            pose[:3, :3] = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) @ pose[:3, :3]
            row["hand_pose"] = pose.reshape(-1).tolist()
            row["wrist_axis"] = pose[:3, 2].tolist()
            row.update(metric_row(rng, blunt=i % 2 == 0))
            if i % 3 == 2:  # a failure: no force closure
                row.update(epsilon=0.0, epsilon_hand=0.0, epsilon_reason="not force closure")
                row["status"] = "touched"
                row.update(
                    {f"hold_effort_{s}": np.inf for s in ("px", "nx", "py", "ny", "pz", "nz")}
                )
                row["impact_effort"] = np.inf
            row.update(
                p0=[0.0] * 6,
                use_dir=[0.0, 0.0],
                n_contacts=len(row["contact_points"]),
                use_triangle=0,
            )
            rows.append(row)
        table = pa.Table.from_pylist(rows, schema=SCHEMA)
        shard = directory / f"shard-{k:03d}.parquet"
        pq.write_table(table, shard)
    (directory / "_manifest.json").write_text("{}")  # not Parquet: must be ignored
    return directory


@pytest.fixture(scope="session")
def block_object(tmp_path_factory):
    path = tmp_path_factory.mktemp("objects2") / "block.stl"
    trimesh.creation.box((0.08, 0.06, 0.05)).export(path)
    return load_object(str(path))
