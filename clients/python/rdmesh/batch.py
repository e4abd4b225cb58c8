"""A dataset through rdmeshd: `rdmesh-py batch` and `Client.batch`, the service's counterpart of
the C++ `rdmesh batch` (docs/BATCH.md, "Through the service").

The inputs, the mirrored output tree, OUTDIR/manifest.jsonl (fields and statuses), resuming,
the partial files and the exit codes follow the C++ batch (clients/cli/batch*.cpp). What
differs: each file is meshed by the server (one address, or replicas behind nginx routed by
the model's sha256, docs/ROUTING.md) and written here; `jobs` requests are in flight at a time,
one thread each; the isolation is the server's (a reader or mesher that crashes or hangs in
one of rdmeshd's worker processes costs that call only), and a file's status comes from the
call's gRPC status (classify()).
"""

import fcntl
import hashlib
import json
import os
import queue
import re
import stat
import sys
import threading
import time
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional

import grpc

from rdmesh.v1 import rdmesh_pb2 as pb

MODEL_EXTENSIONS = (".step", ".stp", ".iges", ".igs", ".brep")
# What this client writes from the arrays the service streams (cli.write_mesh).
FORMATS = ("msh", "stl", "obj", "ply", "vtu")
# Formats of the C++ batch this client cannot write, and what to use instead.
UNSUPPORTED_FORMATS = {
    "glb": "the service streams arrays, not files, and this client has no glTF writer: use "
           "`rdmesh batch --format glb` locally, or `rdmesh mesh --remote ADDRESS FILE -o "
           "OUT.glb` per file",
}
STATUSES = ("ok", "failed", "crashed", "timed_out", "unreadable")
FIELDS = ("path", "sha256", "bytes", "status", "reason", "faces", "faces_failed", "triangles",
          "requested_deviation", "estimated_deviation", "seconds", "output", "reader",
          "exit_code", "signal", "options")

EXIT_OK, EXIT_NOT_OK, EXIT_USAGE, EXIT_INTERRUPTED, EXIT_MANIFEST = 0, 1, 2, 4, 5

# The hidden name a mesh is written under before it is renamed (as the C++ batch's children).
_PARTIAL_NAME = re.compile(r"\..+\.partial(\.lod\d+)?\.[A-Za-z0-9]+")
# Mesh options that do not change the mesh: a file done with other values is not done again.
_NOT_COMPARED = {"threads", "timeout_seconds"}
_SUMMARY_FILES = 5
# A replica that refuses connections (restarting) or a full job queue: waits before retrying.
_RETRY_WAITS = (0.5, 1.0, 2.0, 4.0)
_OUT_OF_MEMORY = ("out of memory", "memory limit", "bad_alloc", "cannot allocate memory",
                  "most likely out of memory")


class BatchError(Exception):
    """Bad usage: an input that does not exist, two inputs writing one output, an unsupported
    format, OUTDIR locked by another run (exit code 2)."""


class _Stopped(Exception):
    """The run was stopped (Ctrl-C twice, SIGTERM) while this file was running."""


# -- inputs --------------------------------------------------------------------------------------

@dataclass
class BatchInput:
    path: str  # absolute, lexically normal (symlinks kept as named)
    output: str  # where its mesh goes, relative to OUTDIR, '/' separated
    listed: bool = False  # named by an @list (a missing one is reported, not refused)


def is_model_file(path):
    return os.path.splitext(path)[1].lower() in MODEL_EXTENSIONS


def _absolute(path):
    return os.path.normpath(os.path.abspath(path))


def _within(path, folder):
    relative = os.path.relpath(path, folder)
    return relative != ".." and not relative.startswith(".." + os.sep)


def _parts(relative):
    return relative.split(os.sep)


def _walk(folder, root, output_dir, listed, found):
    if not os.access(folder, os.R_OK | os.X_OK):
        raise BatchError("cannot read folder '%s'" % folder)
    files = []
    for top, dirs, names in os.walk(folder):
        # The outputs of an earlier run inside the folder are not inputs.
        dirs[:] = [d for d in dirs if os.path.join(top, d) != output_dir]
        for name in names:
            path = os.path.join(top, name)
            if is_model_file(name) and os.path.isfile(path):
                files.append((path, os.path.relpath(path, root), listed))
    files.sort(key=lambda f: _parts(f[1]))  # as the C++ batch: by path element
    found.extend(files)


def _read_list(list_path, output_dir, found):
    try:
        with open(list_path, encoding="utf-8", errors="surrogateescape") as file:
            lines = file.read().splitlines()
    except OSError:
        raise BatchError("cannot read the list '%s'" % list_path) from None
    folder = os.path.dirname(_absolute(list_path))
    entries = []
    for line in lines:
        line = line.strip(" \t\r")
        if not line or line.startswith("#"):
            continue
        entries.append(_absolute(line if os.path.isabs(line) else os.path.join(folder, line)))
    # Mirrored relative to the list's folder, or to what holds every entry when some lie outside.
    root = folder
    if any(not _within(e, folder) for e in entries):
        homes = [e if os.path.isdir(e) else os.path.dirname(e) for e in entries]
        root = os.path.commonpath(homes)
    for entry in entries:
        if os.path.isdir(entry):
            _walk(entry, root, output_dir, True, found)
        else:  # a missing entry stays: the run reports it as unreadable
            found.append((entry, os.path.relpath(entry, root), True))


def _output_name(mirrored, extension, keep):
    name = mirrored + extension if keep else os.path.splitext(mirrored)[0] + extension
    return name.replace(os.sep, "/")


def collect_inputs(args, extension, output_dir) -> List[BatchInput]:
    """The inputs of `args` in order, as the C++ batch collects them (batch_inputs.h): a folder
    gives every model file below it (.step .stp .iges .igs .brep, any case), sorted, mirrored
    relative to the folder; a file gives itself, mirrored as its name; @LIST gives one path per
    line (blank and # lines skipped; relative ones from LIST's folder), mirrored relative to
    LIST's folder or, when some lie outside it, to the deepest folder holding them all. The
    extension is replaced by `extension` (".msh"), kept before it where two inputs would
    otherwise collide. BatchError for a missing argument, an unreadable list, no model file,
    or two inputs that would still write one output."""
    out = _absolute(output_dir)
    found = []
    for arg in args:
        if len(arg) > 1 and arg.startswith("@"):
            _read_list(arg[1:], out, found)
            continue
        path = _absolute(arg)
        if os.path.isdir(path):
            _walk(path, path, out, False, found)
        elif os.path.lexists(path):
            found.append((path, os.path.basename(path), False))
        else:
            raise BatchError("no such file or folder: '%s'" % arg)
    unique, seen = [], set()
    for item in found:  # a file named twice counts once
        if item[0] not in seen:
            seen.add(item[0])
            unique.append(item)
    if not unique:
        raise BatchError("no model files (%s) in the inputs" % " ".join(MODEL_EXTENSIONS))
    by_output: Dict[str, List[int]] = {}
    for i, (_, mirrored, _) in enumerate(unique):
        by_output.setdefault(_output_name(mirrored, extension, False), []).append(i)
    inputs: List[Optional[BatchInput]] = [None] * len(unique)
    for users in by_output.values():
        # Keeping the extension helps only inputs whose mirrored paths differ (a.step, a.stp).
        keep = len(users) > 1 and len({unique[i][1] for i in users}) == len(users)
        for i in users:
            path, mirrored, listed = unique[i]
            inputs[i] = BatchInput(path, _output_name(mirrored, extension, keep), listed)
    owner: Dict[str, int] = {}
    for i, item in enumerate(inputs):
        if not item.output or item.output.startswith("../") or os.path.isabs(item.output):
            raise BatchError("cannot place the output of '%s' under the output folder"
                             % item.path)
        if item.output in owner:
            raise BatchError("'%s' and '%s' would both write '%s': mesh them into separate "
                             "output folders, or list them from one folder"
                             % (inputs[owner[item.output]].path, item.path, item.output))
        owner[item.output] = i
    return inputs


# -- manifest ------------------------------------------------------------------------------------

class Manifest:
    """OUTDIR/manifest.jsonl: one JSON object per input, the latest. A run appends one line per
    finished file (one write(2), so a killed run leaves whole lines) and at its end rewrites the
    file, one line per input, through a partial file renamed over it."""

    def __init__(self, path):
        self.path = path
        self.entries: Dict[str, dict] = {}
        self._seen: List[str] = []
        self._fd = -1

    def load(self):
        """Reads the file (missing = empty); returns how many lines were not entries (the torn
        last line of a killed run)."""
        torn = 0
        if not os.path.exists(self.path):
            return 0
        with open(self.path, encoding="utf-8", errors="replace") as file:
            for line in file:
                if not line.strip():
                    continue
                try:
                    entry = json.loads(line)
                except ValueError:
                    entry = None
                if not isinstance(entry, dict) or not isinstance(entry.get("path"), str):
                    torn += 1
                    continue
                if entry["path"] not in self.entries:
                    self._seen.append(entry["path"])
                self.entries[entry["path"]] = entry
        return torn

    def forget(self, path):
        self.entries.pop(path, None)

    def append(self, entry):
        if entry["path"] not in self.entries:
            self._seen.append(entry["path"])
        self.entries[entry["path"]] = entry
        if self._fd < 0:
            self._fd = os.open(self.path, os.O_RDWR | os.O_APPEND | os.O_CREAT | os.O_CLOEXEC,
                               0o644)
            size = os.lseek(self._fd, 0, os.SEEK_END)
            # A killed run may have left a torn last line: start on a line of our own.
            if size > 0 and os.pread(self._fd, 1, size - 1) != b"\n":
                _write_all(self._fd, b"\n")
        _write_all(self._fd, (_dump(entry) + "\n").encode())

    def rewrite(self, order):
        if self._fd >= 0:
            os.close(self._fd)
            self._fd = -1
        written, lines = set(), []
        for path in list(order) + self._seen:
            if path in self.entries and path not in written:
                written.add(path)
                lines.append(_dump(self.entries[path]) + "\n")
        _write_atomically(self.path, "".join(lines).encode())

    def close(self):
        if self._fd >= 0:
            os.close(self._fd)
            self._fd = -1


def _dump(entry):
    return json.dumps(entry, separators=(",", ":"), ensure_ascii=False)


def _write_all(fd, data):
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view):]


def _write_atomically(path, data):
    partial = path + ".partial"
    fd = os.open(partial, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_CLOEXEC, 0o644)
    try:
        _write_all(fd, data)
        os.fsync(fd)
    finally:
        os.close(fd)
    os.replace(partial, path)


# -- statuses ------------------------------------------------------------------------------------

def classify(code, details, phase):
    """The manifest status of a file whose call ended with gRPC status `code` (a
    grpc.StatusCode) and message `details`, in `phase` ("upload": the model was being sent and
    read; "mesh"). Mirrors the C++ batch's statuses (docs/BATCH.md) on the server's codes
    (docs/SERVICE.md, "Crash isolation"):
    - DEADLINE_EXCEEDED, or a worker past its CPU time limit: timed_out;
    - a worker that crashed (reader or mesher), a model refused as a known crasher, a worker
      killed or out of memory, INTERNAL and other codes: crashed;
    - INVALID_ARGUMENT while reading the model (the upload, or a parse at mesh time:
      "cannot use model ..."), or a model over the server's --max-model-bytes: unreadable;
    - INVALID_ARGUMENT or FAILED_PRECONDITION about the mesh (options beyond the model), a mesh
      over the server's --max-triangles: failed."""
    text = (details or "").lower()
    if code == grpc.StatusCode.DEADLINE_EXCEEDED or "cpu time limit" in text:
        return "timed_out"
    if "crashed (" in text or any(sign in text for sign in _OUT_OF_MEMORY):
        return "crashed"
    if code == grpc.StatusCode.INVALID_ARGUMENT:
        return "unreadable" if phase == "upload" or "cannot use model" in text else "failed"
    if code == grpc.StatusCode.RESOURCE_EXHAUSTED:
        if "max-model-bytes" in text:
            return "unreadable"
        if "max-triangles" in text:
            return "failed"
        return "crashed"
    if code == grpc.StatusCode.FAILED_PRECONDITION:
        return "failed"
    return "crashed"


def _transient(code, details):
    """A refusal that says nothing of the file: retried after a wait."""
    if code == grpc.StatusCode.UNAVAILABLE:
        return True
    return code == grpc.StatusCode.RESOURCE_EXHAUSTED and "queue is full" in (details or "")


def option_strings(options):
    """The manifest's `options`: the mesh options given, as `--flag`: "value" strings (those
    that do not change the mesh left out); a file done with other options is done again."""
    shown = {}
    for key, value in options.items():
        if value is None or key in _NOT_COMPARED or value is False:
            continue
        if key == "face_ids":
            value = ",".join(str(int(v)) for v in value)
        elif value is True:
            value = "true"
        shown["--" + key.replace("_", "-")] = str(value)
    return shown


# -- the run -------------------------------------------------------------------------------------

@dataclass
class BatchProgress:
    """Where a run is: `done` of `total` files finished or skipped, `processed` of them meshed
    (or found unreadable) by this run, `failures` not ok, `seconds` since the start."""
    done: int
    total: int
    processed: int
    failures: int
    seconds: float

    @property
    def files_per_minute(self):
        return 60.0 * self.processed / self.seconds if self.seconds > 0 else 0.0

    @property
    def eta_seconds(self):
        rate = self.processed / self.seconds if self.seconds > 0 else 0.0
        return (self.total - self.done) / rate if rate > 0 else None


@dataclass
class BatchSummary:
    """The end of a run: counts per status, throughput, the slowest and the worst files."""
    files: int
    meshed: int
    skipped: int
    not_done: int
    interrupted: bool
    counts: Dict[str, int]
    seconds: float
    files_per_minute: float
    jobs: int
    slowest: List[str]
    worst: List[str]
    manifest: str
    exit_code: int
    entries: List[Optional[dict]] = field(default_factory=list, repr=False)
    slowest_seconds: List[float] = field(default_factory=list, repr=False)
    # per worst file: its failed faces, its faces, and its estimated deviation over the request
    worst_notes: List[tuple] = field(default_factory=list, repr=False)

    def as_json(self):
        return {"files": self.files, "meshed": self.meshed, "skipped": self.skipped,
                "not_done": self.not_done, "interrupted": self.interrupted,
                "counts": self.counts, "seconds": self.seconds,
                "files_per_minute": self.files_per_minute, "jobs": self.jobs,
                "slowest": self.slowest, "worst": self.worst, "manifest": self.manifest}


class Batch:
    """One run. `client` is an rdmesh.Client (its channel is shared by the threads); `inputs`
    as collect_inputs() takes them; `options` are Client.mesh()'s mesh options. run() returns a
    BatchSummary; stop() (from another thread or a signal handler) lets the running files
    finish and starts no more; kill() also cancels the running calls (they are not recorded:
    the next run does them)."""

    def __init__(self, client, inputs, output_dir, format="msh", jobs=4, timeout=None,
                 progress: Optional[Callable[[BatchProgress], None]] = None,
                 problem: Optional[Callable[[str], None]] = None, **options):
        from rdmesh.client import mesh_options
        fmt = format.lower().lstrip(".")
        if fmt in UNSUPPORTED_FORMATS:
            raise BatchError("--format %s: not written by rdmesh-py: %s"
                             % (fmt, UNSUPPORTED_FORMATS[fmt]))
        if fmt not in FORMATS:
            raise BatchError("--format %s: not an output format (rdmesh-py writes %s)"
                             % (format, ", ".join(FORMATS)))
        if int(jobs) < 1:
            raise BatchError("--jobs must be 1 or more")
        if timeout is not None and timeout < 0:
            raise BatchError("--timeout must be 0 (none) or more seconds")
        for key, value in options.items():
            if isinstance(value, (int, float)) and not isinstance(value, bool) and value < 0:
                raise BatchError("%s must not be negative" % key)
        mesh_options(**options)  # unknown options fail before anything runs
        self.client = client
        self.format = fmt
        self.extension = "." + fmt
        self.jobs = int(jobs)
        self.timeout = timeout or None
        self.options = options
        self.options_shown = option_strings(options)
        self.progress = progress
        self.problem = problem or (lambda line: None)
        self.out = _absolute(output_dir)
        self.inputs = (inputs if inputs and isinstance(inputs[0], BatchInput)
                       else collect_inputs(list(inputs), self.extension, self.out))
        self.manifest = Manifest(os.path.join(self.out, "manifest.jsonl"))
        self._lock = threading.RLock()
        self._next = 0
        self._stopping = False
        self._killed = False
        self._calls: Dict[int, object] = {}  # input index -> its call in flight (cancel())
        self._lock_fd = -1

    # -- control (any thread) --

    def stop(self):
        """No new files start; the running ones finish and are recorded."""
        self._stopping = True

    def kill(self):
        """Stops at once: the running calls are cancelled and their files not recorded."""
        with self._lock:
            self._stopping = self._killed = True
            calls = list(self._calls.values())
        for call in calls:
            call.cancel()

    @property
    def stopping(self):
        return self._stopping

    # -- the run --

    def run(self) -> BatchSummary:
        self._check_options()
        self._prepare()
        try:
            return self._run()
        finally:
            self.manifest.close()
            if self._lock_fd >= 0:
                os.close(self._lock_fd)

    def _check_options(self):
        """The mesh options, checked once by the server before anything runs (as the C++ batch
        checks them, exit 2): it checks a Mesh request's options before it looks for the model,
        so a request for a model no server holds answers NOT_FOUND when they are good."""
        from rdmesh.client import RdmeshError, _Model
        nobody = "0" * 64
        try:
            call = self.client._mesh_call(_Model(pb.ModelRef(model_id=nobody), nobody), False,
                                          False, 30.0, self.options)
            for _ in call:
                pass
        except (RdmeshError, grpc.RpcError) as error:
            code = error.code if isinstance(error, RdmeshError) else error.code()
            details = error.details if isinstance(error, RdmeshError) else error.details()
            if code == grpc.StatusCode.INVALID_ARGUMENT:
                raise BatchError("the server refuses the mesh options: %s" % details) from None
            if code != grpc.StatusCode.NOT_FOUND:
                raise BatchError("cannot check the mesh options with the server: %s: %s"
                                 % (code.name if code else "UNKNOWN", details)) from None

    def _prepare(self):
        try:
            os.makedirs(self.out, exist_ok=True)
        except OSError as error:
            raise BatchError("cannot create '%s': %s" % (self.out, error.strerror)) from None
        lock = os.path.join(self.out, ".rdmesh-batch.lock")
        try:
            self._lock_fd = os.open(lock, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
        except OSError as error:
            raise BatchError("cannot write '%s': %s" % (lock, error.strerror)) from None
        try:
            fcntl.flock(self._lock_fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(self._lock_fd)
            self._lock_fd = -1
            raise BatchError("another batch is writing '%s'" % self.out) from None
        torn = self.manifest.load()
        if torn:
            self.problem("skipped %d unreadable line(s) of the manifest (a run killed while "
                         "writing it)" % torn)
        # An earlier input whose output a new input takes is no longer in the tree.
        owners = {i.output: i.path for i in self.inputs}
        stale = [path for path, entry in self.manifest.entries.items()
                 if isinstance(entry.get("output"), str)
                 and owners.get(entry["output"], path) != path]
        for path in stale:
            self.manifest.forget(path)
        # A killed run leaves partial files ('.NAME.EXT.partial.EXT'): removed.
        for top, _, names in os.walk(self.out):
            for name in names:
                if _PARTIAL_NAME.fullmatch(name):
                    try:
                        os.remove(os.path.join(top, name))
                    except OSError:
                        pass

    def _run(self):
        n = len(self.inputs)
        self.entries: List[Optional[dict]] = [None] * n
        self.counts = {s: 0 for s in STATUSES}
        self.recorded: List[int] = []
        self.skipped = self.processed = 0
        manifest_error = None
        results: "queue.Queue" = queue.Queue()
        start = time.monotonic()
        threads = [threading.Thread(target=self._worker, args=(results,), daemon=True,
                                    name="rdmesh-batch-%d" % i)
                   for i in range(min(self.jobs, n))]
        for thread in threads:
            thread.start()
        last_shown = 0.0
        while True:
            try:
                kind, index, entry = results.get(timeout=0.25)
            except queue.Empty:
                kind = None
            if kind == "skipped":
                self.skipped += 1
                self.counts["ok"] += 1
                self.entries[index] = entry
            elif kind == "recorded":
                self.processed += 1
                error = self._record(index, entry)
                manifest_error = manifest_error or error
            if kind is None and not any(t.is_alive() for t in threads) and results.empty():
                break
            now = time.monotonic()
            if self.progress and (now - last_shown >= 0.25 or kind is None):
                last_shown = now
                self._show(n, now - start)
        seconds = time.monotonic() - start
        if self.progress:
            self._show(n, seconds)
        interrupted = self._stopping and self.skipped + self.processed < n
        self._remove_empty_folders()
        try:
            self.manifest.rewrite([i.path for i in self.inputs])
        except OSError as error:
            manifest_error = manifest_error or error
        if manifest_error is not None:
            code = EXIT_MANIFEST
            self.problem("cannot write the manifest: %s" % manifest_error)
        elif interrupted:
            code = EXIT_INTERRUPTED
        else:
            code = EXIT_OK if self.counts["ok"] == n else EXIT_NOT_OK
        return self._summary(seconds, interrupted, code)

    def _show(self, n, seconds):
        failures = sum(c for s, c in self.counts.items() if s != "ok")
        self.progress(BatchProgress(self.skipped + self.processed, n, self.processed, failures,
                                    seconds))

    def _record(self, index, entry):
        self.counts[entry["status"]] += 1
        if entry["status"] != "ok":
            self.problem("%s: %s: %s" % (entry["status"], entry["path"], entry["reason"]))
        self.entries[index] = entry
        self.recorded.append(index)
        try:
            self.manifest.append(entry)
        except OSError as error:
            return error
        return None

    def _worker(self, results):
        while True:
            with self._lock:
                if self._stopping or self._next >= len(self.inputs):
                    return
                index = self._next
                self._next += 1
            try:
                results.put(self._file(index))
            except _Stopped:
                pass
            except Exception as error:  # noqa: BLE001 - a bug here costs this file only
                entry = self._new_entry(index)
                entry.update(status="crashed", reason="rdmesh-py: %s: %s"
                             % (type(error).__name__, error))
                results.put(("recorded", index, entry))

    def _new_entry(self, index, sha256=None, size=None):
        return {"path": self.inputs[index].path, "sha256": sha256, "bytes": size, "status": "",
                "reason": "", "faces": None, "faces_failed": None, "triangles": None,
                "requested_deviation": None, "estimated_deviation": None, "seconds": 0.0,
                "output": None, "reader": None, "exit_code": None, "signal": None,
                "options": dict(self.options_shown), "grpc_code": None}

    def _file(self, index):
        """Reads, hashes, skips or meshes one input; ("skipped" | "recorded", index, entry)."""
        item = self.inputs[index]
        problem, data = None, None
        try:
            mode = os.stat(item.path).st_mode
            if not stat.S_ISREG(mode):
                problem = "not a regular file"  # a FIFO is never opened
            else:
                with open(item.path, "rb") as file:
                    data = file.read()
        except FileNotFoundError:
            problem = "no such file"
        except OSError as error:
            problem = "cannot read it: %s" % (error.strerror or error)
        if problem is not None:
            entry = self._new_entry(index)
            entry.update(status="unreadable", reason=problem)
            return "recorded", index, entry
        sha256 = hashlib.sha256(data).hexdigest()
        final = os.path.join(self.out, item.output)
        old = self.manifest.entries.get(item.path)
        if (old is not None and old.get("status") == "ok" and old.get("sha256") == sha256
                and old.get("output") == item.output
                and old.get("options", {}) == self.options_shown and os.path.isfile(final)):
            return "skipped", index, old
        entry = self._new_entry(index, sha256, len(data))
        start = time.monotonic()
        partial = os.path.join(os.path.dirname(final),
                               "." + os.path.basename(final) + ".partial" + self.extension)
        keep = stopped = False
        try:
            result = self._mesh(index, item, data, sha256, entry, start)
            del data
            if result is not None:
                keep = self._write(result, partial, final, entry)
        except _Stopped:
            stopped = True
            raise
        finally:
            # Without a mesh, an older output of this path goes too (as the C++ batch); a
            # stopped file is not done, and what an earlier run left stays.
            for path in ([] if keep else [partial] if stopped else [partial, final]):
                try:
                    os.remove(path)
                except OSError:
                    pass
        entry["seconds"] = time.monotonic() - start
        if keep:
            entry["output"] = item.output
        return "recorded", index, entry

    def _remaining(self, start):
        if self.timeout is None:
            return None
        return self.timeout - (time.monotonic() - start)

    def _track(self, index, call):
        with self._lock:
            self._calls[index] = call
            killed = self._killed
        if killed:
            call.cancel()

    def _untrack(self, index):
        with self._lock:
            self._calls.pop(index, None)

    def _mesh(self, index, item, data, sha256, entry, start):
        """The upload (when the server does not hold the model) and the Mesh call; the
        MeshResult, or None with the entry's status and reason set."""
        from rdmesh.client import RdmeshError, _Model
        client = self.client
        model = _Model(pb.ModelRef(model_id=sha256), sha256, path=item.path, data=data)
        want_deviation = self.format in ("ply", "vtu")
        uploaded = False
        phase = "mesh"
        attempt = 0
        while True:
            remaining = self._remaining(start)
            if remaining is not None and remaining <= 0:
                code, details = grpc.StatusCode.DEADLINE_EXCEEDED, "deadline passed"
                break
            try:
                if phase == "upload":
                    self._upload(index, client, model, data, item, remaining)
                    uploaded = True
                    phase = "mesh"
                    continue
                call = client._mesh_call(model, False, False, remaining, self.options,
                                         triangle_deviation=want_deviation)
                self._track(index, call)
                try:
                    result = client._collect(call, None)
                finally:
                    self._untrack(index)
                entry["grpc_code"] = "OK"
                return result
            except (RdmeshError, grpc.RpcError, grpc.FutureCancelledError) as error:
                if isinstance(error, grpc.FutureCancelledError):
                    code, details = grpc.StatusCode.CANCELLED, "cancelled"
                elif isinstance(error, RdmeshError):
                    code, details = error.code, error.details
                else:
                    code, details = error.code(), error.details()
            if self._killed:
                raise _Stopped()
            if code == grpc.StatusCode.NOT_FOUND and phase == "mesh" and not uploaded:
                phase = "upload"
                continue
            if _transient(code, details) and attempt < len(_RETRY_WAITS):
                wait = _RETRY_WAITS[attempt]
                attempt += 1
                # A replica that went away takes the model with it: the next one on nginx's
                # ring answers NOT_FOUND and gets the file once more (docs/ROUTING.md).
                uploaded = False
                remaining = self._remaining(start)
                if remaining is None or remaining > wait:
                    time.sleep(wait)
                    continue
            break
        entry["grpc_code"] = code.name if code is not None else "UNKNOWN"
        status = classify(code, details, phase)
        if status == "timed_out" and code == grpc.StatusCode.DEADLINE_EXCEEDED:
            reason = "no result within --timeout %g s (%s)" % (
                self.timeout or 0, "reading the model" if phase == "upload" else "meshing")
            if details and details not in ("deadline passed", "Deadline Exceeded"):
                reason += ": " + details
        else:
            reason = details or "the call ended with %s" % entry["grpc_code"]
        if code == grpc.StatusCode.NOT_FOUND:
            reason += " (after its upload)"
        entry.update(status=status, reason=reason)
        return None

    def _upload(self, index, client, model, data, item, remaining):
        from rdmesh.client import CHUNK_BYTES

        def chunks():
            yield pb.ModelChunk(data=data[:CHUNK_BYTES], name=os.path.basename(item.path),
                                total_bytes=len(data))
            for offset in range(CHUNK_BYTES, len(data), CHUNK_BYTES):
                yield pb.ModelChunk(data=data[offset:offset + CHUNK_BYTES])

        future = client._stub.UploadModel.future(chunks(), timeout=remaining,
                                                 metadata=client._metadata_for(model.key))
        self._track(index, future)
        try:
            return future.result()
        finally:
            self._untrack(index)

    def _write(self, result, partial, final, entry):
        """Fills the entry from the result and writes the mesh to `partial`, then renames it to
        `final`; whether the mesh was kept."""
        from rdmesh.cli import write_mesh
        s = result.summary
        faces_failed = int(s.faces_failed)
        entry.update(faces=int(s.faces_ok + s.faces_failed + s.faces_skipped),
                     faces_failed=faces_failed, triangles=int(len(result.triangles)),
                     requested_deviation=s.requested_deviation,
                     estimated_deviation=s.estimated_deviation)
        total = entry["faces"]
        if faces_failed:
            entry["status"] = "failed"
            entry["reason"] = _face_reasons(result.faces, "failed", faces_failed, total,
                                            "failed")
        else:
            entry["status"] = "ok"
            over = sum(1 for f in result.faces if f.status == "ok" and f.reason)
            if over:
                entry["reason"] = _face_reasons(result.faces, "ok", over, total,
                                                "meshed over the criteria")
        try:
            os.makedirs(os.path.dirname(final), exist_ok=True)
            write_mesh(partial, result)
            if self._killed:
                raise _Stopped()
            os.replace(partial, final)
        except OSError as error:
            entry["status"] = "failed"
            entry["reason"] = "cannot write the mesh to '%s': %s" % (
                final, error.strerror or error)
            return False
        return True

    def _remove_empty_folders(self):
        """The folders made for files that left no mesh."""
        for item in self.inputs:
            folder = os.path.dirname(os.path.join(self.out, item.output))
            while len(folder) > len(self.out) and folder != self.out:
                try:
                    os.rmdir(folder)
                except OSError:
                    break
                folder = os.path.dirname(folder)

    def _summary(self, seconds, interrupted, code):
        n = len(self.inputs)

        def badness(i):
            e = self.entries[i]
            requested = e.get("requested_deviation") or 0.0
            estimated = e.get("estimated_deviation") or 0.0
            return (e.get("faces_failed") or 0, estimated / requested if requested > 0 else 0.0)

        slowest = sorted(self.recorded, key=lambda i: -self.entries[i]["seconds"])
        worst = [i for i in self.recorded if self.entries[i].get("faces_failed") is not None
                 and (badness(i)[0] > 0 or badness(i)[1] > 1.0)]
        worst.sort(key=badness, reverse=True)
        summary = BatchSummary(
            files=n, meshed=self.processed, skipped=self.skipped,
            not_done=n - self.skipped - self.processed, interrupted=interrupted,
            counts=dict(self.counts), seconds=seconds,
            files_per_minute=60.0 * self.processed / seconds if seconds > 0 else 0.0,
            jobs=self.jobs, slowest=[self.inputs[i].path for i in slowest[:_SUMMARY_FILES]],
            worst=[self.inputs[i].path for i in worst[:_SUMMARY_FILES]],
            manifest=self.manifest.path, exit_code=code, entries=self.entries,
            slowest_seconds=[self.entries[i]["seconds"] for i in slowest[:_SUMMARY_FILES]],
            worst_notes=[(badness(i)[0], self.entries[i].get("faces"), badness(i)[1])
                         for i in worst[:_SUMMARY_FILES]])
        return summary


def _face_reasons(faces, status, count, total, what):
    """'2 of 16 faces meshed over the criteria; face 2 (cylinder): reason', the first named."""
    first = ""
    for face in faces:
        if face.status == status and (status != "ok" or face.reason):
            first = "face %d (%s): %s" % (face.face_id, face.surface_type,
                                          face.reason or "no reason given")
            break
    return "%d of %d faces %s%s" % (count, total, what, "; " + first if first else "")


# -- what the command prints ---------------------------------------------------------------------

def duration(seconds):
    s = int(round(seconds))
    if s >= 3600:
        return "%dh%02dm" % (s // 3600, (s // 60) % 60)
    if s >= 60:
        return "%dm%02ds" % (s // 60, s % 60)
    return "%ds" % s


class Display:
    """The one-line progress on a terminal (stderr) and a line per file that was not ok."""

    def __init__(self, quiet, stream=None, prefix="rdmesh-py batch"):
        self.stream = stream or sys.stderr
        self.quiet = quiet
        self.prefix = prefix
        self.terminal = not quiet and self.stream.isatty()
        self.shown = False
        self._lock = threading.RLock()

    def problem(self, line):
        if self.quiet:
            return
        with self._lock:
            self._erase()
            self.stream.write("%s: %s\n" % (self.prefix, line))
            self.stream.flush()

    def progress(self, p: BatchProgress):
        if not self.terminal:
            return
        line = "%s: %d/%d done, %d not ok" % (self.prefix, p.done, p.total, p.failures)
        if p.processed and p.seconds > 0:
            line += ", %.1f files/min, ETA %s" % (p.files_per_minute, duration(p.eta_seconds))
        with self._lock:
            self.stream.write("\r\033[K" + line)
            self.stream.flush()
            self.shown = True

    def erase(self):
        with self._lock:
            self._erase()

    def _erase(self):
        if self.shown:
            self.stream.write("\r\033[K")
            self.stream.flush()
            self.shown = False


def summary_text(summary: BatchSummary, prefix="rdmesh-py batch"):
    """The end summary, as the C++ batch prints it."""
    lines = ["%s: %d files, %d meshed in %s (%.1f files/min, --jobs %d), %d skipped (done "
             "before)%s" % (prefix, summary.files, summary.meshed, duration(summary.seconds),
                            summary.files_per_minute, summary.jobs, summary.skipped,
                            ", %d not done (interrupted)" % summary.not_done
                            if summary.interrupted else ""),
             " " + "".join(" %s %d" % (s, summary.counts.get(s, 0)) for s in STATUSES)]
    if summary.slowest:
        lines.append("  slowest:")
        for path, seconds in zip(summary.slowest, summary.slowest_seconds):
            lines.append("    %7.2f s  %s" % (seconds, path))
    if summary.worst:
        lines.append("  worst:")
        for path, (failed, faces, ratio) in zip(summary.worst, summary.worst_notes):
            if failed:
                lines.append("    %s: %d of %s faces failed" % (path, failed, faces))
            else:
                lines.append("    %s: estimated deviation %.2fx the request" % (path, ratio))
    lines.append("  manifest: %s" % summary.manifest)
    return "\n".join(lines)


__all__ = ["Batch", "BatchError", "BatchInput", "BatchProgress", "BatchSummary", "Display",
           "FORMATS", "FIELDS", "Manifest", "STATUSES", "UNSUPPORTED_FORMATS", "classify",
           "collect_inputs", "summary_text", "EXIT_OK", "EXIT_NOT_OK", "EXIT_USAGE",
           "EXIT_INTERRUPTED", "EXIT_MANIFEST"]
