# SPDX-License-Identifier: MIT
"""isokit-batch: bake a manifest of jobs in parallel, on this machine or on a Dask cluster.

Installed as ``isokit.batch`` (so that every worker that has isokit can run jobs) and run as
``isokit-batch MANIFEST`` (apps/batch/isokit-batch) or ``python3 -m isokit.batch MANIFEST``.
docs/batch.md describes the manifest, the outputs and the rules; in short:

- each job (rig, animation, method, setup, outputs) is independent; its outputs are written
  atomically (a temporary file renamed), so a crash never leaves a half-written file;
- a failed job is a row with its error; the other jobs go on;
- a job is identified by a key of its content (the bytes of its rig and setup files, its
  parameters and the isokit version): a rerun skips the jobs whose key is recorded as done and
  whose outputs exist;
- a worker that cannot read a job's files, or runs another isokit version than the one that
  submitted the job, fails that job with a message saying so.
"""
import argparse
import concurrent.futures
import hashlib
import json
import os
import socket
import sys
import time

FORMAT = "isokit-batch"
VERSION = 1
STATE_DIR = ".isokit-batch"
_JOB_KEYS = {"name", "rig", "clip", "bends", "frames", "pose_script", "method", "setup", "fps", "outputs",
             "self_intersections"}
_OUTPUT_KEYS = {"glb", "pc2", "metrics"}


class ManifestError(ValueError):
    """A manifest that cannot be run; the message names the file and the item."""


def _isokit_version():
    import isokit

    return isokit.__version__


def _default_method():
    """isokit's default method (isokit.skinning.DEFAULT_METHOD: the score's first implicit method)."""
    from isokit import skinning
    return skinning.DEFAULT_METHOD


def load_manifest(path):
    """The manifest's jobs as dicts with absolute paths (relative ones are relative to the manifest).

    Raises ManifestError naming the manifest and the item for anything malformed.
    """
    try:
        with open(path, encoding="utf-8") as f:
            doc = json.load(f)
    except OSError as e:
        raise ManifestError(f"{path}: cannot be read ({e.strerror}); check the path") from e
    except json.JSONDecodeError as e:
        raise ManifestError(f"{path}: not valid JSON ({e}); fix the file") from e
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise ManifestError(f'{path}: "format" must be "{FORMAT}"; see docs/batch.md')
    if doc.get("version") != VERSION:
        raise ManifestError(f'{path}: "version" must be {VERSION} (got {doc.get("version")!r})')
    jobs = doc.get("jobs")
    if not isinstance(jobs, list) or not jobs:
        raise ManifestError(f'{path}: "jobs" must be a non-empty list')
    base = os.path.dirname(os.path.abspath(path))
    defaults = doc.get("defaults", {})
    names = set()
    out = []
    for i, job in enumerate(jobs):
        where = f"{path}: jobs[{i}]"
        if not isinstance(job, dict):
            raise ManifestError(f"{where}: must be an object")
        job = {**defaults, **job}
        unknown = set(job) - _JOB_KEYS
        if unknown:
            raise ManifestError(f"{where}: unknown key(s) {sorted(unknown)}; known: {sorted(_JOB_KEYS)}")
        for key in ("rig", "outputs"):
            if key not in job:
                raise ManifestError(f'{where}: "{key}" is missing')
        if "method" not in job:  # isokit's default, fixed here so that the job's key names it
            job["method"] = _default_method()
        name = job.get("name", f"job{i}")
        if name in names:
            raise ManifestError(f'{where}: the name "{name}" is used twice')
        names.add(name)
        outputs = job["outputs"]
        if not isinstance(outputs, dict) or not outputs or set(outputs) - _OUTPUT_KEYS:
            raise ManifestError(f'{where}.outputs: must map some of {sorted(_OUTPUT_KEYS)} to paths')

        def resolve(p):
            return p if p.startswith("procedural:") or os.path.isabs(p) else os.path.join(base, p)

        resolved = dict(job, name=name, rig=resolve(job["rig"]),
                        outputs={k: resolve(v) for k, v in outputs.items()})
        for key in ("setup", "pose_script"):
            if key in job:
                resolved[key] = resolve(job[key])
        out.append(resolved)
    return out, base


def _file_digest(path, h):
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)


def job_key(job, version):
    """A key of everything a job's result depends on: its files' bytes, parameters, isokit's version.

    Paths are not part of it (moving the inputs does not redo a job); a file that cannot be read is
    keyed by its path, and the job then fails on the worker.
    """
    h = hashlib.sha256()
    params = {k: v for k, v in job.items() if k not in ("name", "outputs", "rig", "setup", "pose_script")}
    h.update(json.dumps({"params": params, "version": version,
                         "outputs": sorted(job["outputs"])}, sort_keys=True).encode())
    for key in ("rig", "setup", "pose_script"):
        p = job.get(key)
        if p is None:
            continue
        h.update(key.encode())
        if p.startswith("procedural:") or not os.path.isfile(p):
            h.update(p.encode())
        else:
            _file_digest(p, h)
    return h.hexdigest()[:32]


def _write_atomically(path, text):
    os.makedirs(os.path.dirname(os.path.abspath(path)) or ".", exist_ok=True)
    tmp = f"{path}.tmp-{os.getpid()}"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(text)
    os.replace(tmp, path)


def run_job(job, version):
    """Runs one job where it is called (a pool process or a Dask worker); returns a result row.

    Never raises: a failure is a row with status "failed" and the error's one-line message.
    """
    t0 = time.perf_counter()
    row = {"name": job["name"], "status": "done", "seconds": 0.0, "error": "", "host": socket.gethostname()}
    try:
        import isokit
        from isokit import skinning

        if isokit.__version__ != version:
            raise RuntimeError(
                f"worker {row['host']} runs isokit {isokit.__version__}, the job was submitted with {version}: "
                "install the same isokit on every worker")
        for key in ("rig", "setup", "pose_script"):
            p = job.get(key)
            if p is not None and not p.startswith("procedural:") and not os.access(p, os.R_OK):
                raise RuntimeError(f"worker {row['host']} cannot read the job's {key} {p}: "
                                   "give every worker the same paths (a shared folder)")
        rig = skinning.load(job["rig"], fps=float(job.get("fps", 30)))
        skinner = skinning.Skinner(rig, setup=job.get("setup"))
        result = skinner.bake(job["method"], clip=job.get("clip"), bends=job.get("bends", []),
                              pose_script=job.get("pose_script"), frames=int(job.get("frames", 31)),
                              self_intersections=bool(job.get("self_intersections", False)))
        outputs = job["outputs"]
        for key, path in outputs.items():
            os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        if "glb" in outputs:
            result.write_glb(outputs["glb"])  # atomic (isokit's writers)
        if "pc2" in outputs:
            result.write_pc2(outputs["pc2"])
        if "metrics" in outputs:
            _write_atomically(outputs["metrics"], json.dumps(result.metrics(), indent=1, sort_keys=True))
    except Exception as e:  # one row per failure; the batch goes on
        row["status"] = "failed"
        row["error"] = " ".join(f"{type(e).__name__}: {e}".split())
    row["seconds"] = time.perf_counter() - t0
    return row


def _state_path(base, key):
    return os.path.join(base, STATE_DIR, key + ".json")


def _finished(base, job, key):
    state = _state_path(base, key)
    return os.path.isfile(state) and all(os.path.isfile(p) for p in job["outputs"].values())


def _record(base, job, key, row):
    _write_atomically(_state_path(base, key), json.dumps({"name": job["name"], "outputs": job["outputs"],
                                                          "seconds": row["seconds"]}))


class _Progress:
    """A one-line progress bar on stderr (a plain line per job when stderr is not a terminal)."""

    def __init__(self, total, stream=sys.stderr):
        self.total, self.done, self.stream = total, 0, stream
        self.tty = hasattr(stream, "isatty") and stream.isatty()

    def step(self, row):
        self.done += 1
        if self.tty:
            width = 30
            filled = width * self.done // max(self.total, 1)
            self.stream.write(f"\r[{'#' * filled}{'.' * (width - filled)}] {self.done}/{self.total} {row['name'][:30]:30}")
            if self.done == self.total:
                self.stream.write("\n")
        else:
            self.stream.write(f"isokit-batch: {self.done}/{self.total} {row['name']}: {row['status']}\n")
        self.stream.flush()


def run_batch(manifest, scheduler=None, workers=None, progress=True):
    """Runs a manifest; returns the rows (one per job, in manifest order).

    `scheduler`: the address of a Dask scheduler, or a `distributed.Client`; None runs the jobs
    in a process pool of `workers` processes (default: the CPU count).
    """
    jobs, base = load_manifest(manifest)
    version = _isokit_version()
    keys = [job_key(job, version) for job in jobs]
    rows = [None] * len(jobs)
    todo = []
    for i, (job, key) in enumerate(zip(jobs, keys)):
        if _finished(base, job, key):
            rows[i] = {"name": job["name"], "status": "skipped", "seconds": 0.0, "error": "", "host": ""}
        else:
            todo.append(i)
    bar = _Progress(len(jobs)) if progress else None
    for i in range(len(jobs)):
        if rows[i] is not None and bar:
            bar.step(rows[i])

    def finish(i, row):
        rows[i] = row
        if row["status"] == "done":
            _record(base, jobs[i], keys[i], row)
        if bar:
            bar.step(row)

    if todo and scheduler is not None:
        import distributed

        client = scheduler if isinstance(scheduler, distributed.Client) else distributed.Client(scheduler)
        try:
            futures = {client.submit(run_job, jobs[i], version, pure=False): i for i in todo}
            for future in distributed.as_completed(futures):
                i = futures[future]
                try:
                    finish(i, future.result())
                except Exception as e:  # the worker died, or could not import isokit
                    finish(i, {"name": jobs[i]["name"], "status": "failed", "seconds": 0.0,
                               "error": f"the Dask worker failed: {type(e).__name__}: {e}", "host": ""})
        finally:
            if client is not scheduler:
                client.close()
    elif todo:
        with concurrent.futures.ProcessPoolExecutor(max_workers=workers or os.cpu_count()) as pool:
            futures = {pool.submit(run_job, jobs[i], version): i for i in todo}
            for future in concurrent.futures.as_completed(futures):
                i = futures[future]
                try:
                    finish(i, future.result())
                except Exception as e:  # the pool process died
                    finish(i, {"name": jobs[i]["name"], "status": "failed", "seconds": 0.0,
                               "error": f"the worker process failed: {type(e).__name__}: {e}", "host": ""})
    return rows


def summary_table(rows):
    """The summary as a Markdown table: job, status, seconds, error."""
    lines = ["| job | status | seconds | error |", "|---|---|---:|---|"]
    for r in rows:
        lines.append(f"| {r['name']} | {r['status']} | {r['seconds']:.2f} | {r['error']} |")
    done = sum(r["status"] == "done" for r in rows)
    skipped = sum(r["status"] == "skipped" for r in rows)
    failed = sum(r["status"] == "failed" for r in rows)
    lines.append("")
    lines.append(f"{done} done, {skipped} skipped (already done), {failed} failed")
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(prog="isokit-batch", description="Bake a manifest of skinning jobs in parallel "
                                     "(a process pool, or a Dask cluster with --scheduler); docs/batch.md")
    parser.add_argument("manifest", help="the manifest JSON file")
    parser.add_argument("--scheduler", help="address of a Dask scheduler (e.g. tcp://10.0.0.1:8786)")
    parser.add_argument("--workers", type=int, help="processes of the local pool (default: the CPU count)")
    parser.add_argument("--no-progress", action="store_true", help="no progress output")
    args = parser.parse_args(argv)
    try:
        rows = run_batch(args.manifest, scheduler=args.scheduler, workers=args.workers,
                         progress=not args.no_progress)
    except ManifestError as e:
        print(f"isokit-batch: error: {e}", file=sys.stderr)
        return 2
    print(summary_table(rows))
    return 1 if any(r["status"] == "failed" for r in rows) else 0


if __name__ == "__main__":
    sys.exit(main())
