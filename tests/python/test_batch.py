# SPDX-License-Identifier: MIT
"""isokit-batch: a 6-job manifest on a process pool and on a Dask LocalCluster of 2 workers."""
import json
import os
import subprocess
import sys

import pytest

pytest.importorskip("isokit.skinning", reason="isokit built without the skinning library")
from isokit import batch  # noqa: E402


def write_manifest(folder, bad_rig):
    jobs = []
    for method in ("dqs", "tracking2014"):
        for degrees in (40, 80):
            name = f"{method}-{degrees}"
            jobs.append({"name": name, "method": method, "bends": [f"Bone1:x:{degrees}"],
                         "outputs": {"pc2": f"out/{name}.pc2", "glb": f"out/{name}.glb", "metrics": f"out/{name}.json"}})
    jobs.append({"name": "lbs-clip-free", "method": "lbs", "bends": ["Bone1:z:30"], "outputs": {"pc2": "out/lbs.pc2"}})
    for method in ("ddm", "cor"):
        jobs.append({"name": f"{method}-40", "method": method, "bends": ["Bone1:x:40"],
                     "outputs": {"pc2": f"out/{method}.pc2", "metrics": f"out/{method}.json"}})
    jobs.append({"name": "bad-file", "rig": bad_rig, "method": "dqs", "outputs": {"pc2": "out/bad.pc2"}})
    manifest = {"format": "isokit-batch", "version": 1,
                "defaults": {"rig": "procedural:cylinder?vertices=1000", "frames": 5}, "jobs": jobs}
    path = folder / "manifest.json"
    path.write_text(json.dumps(manifest))
    return path


def outputs_of(folder):
    out = folder / "out"
    return {p.name: p.read_bytes() for p in sorted(out.iterdir()) if p.suffix in (".pc2", ".glb")}


@pytest.fixture(scope="module")
def two_runs(tmp_path_factory):
    """The manifest run with the process pool and on Dask, each in its own folder."""
    results = {}
    for kind in ("pool", "dask"):
        folder = tmp_path_factory.mktemp(kind)
        (folder / "broken.glb").write_bytes(b"not a glTF file")
        manifest = write_manifest(folder, "broken.glb")
        if kind == "pool":
            rows = batch.run_batch(manifest, workers=2, progress=False)
        else:
            distributed = pytest.importorskip("distributed")
            with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                          dashboard_address=None) as cluster, distributed.Client(cluster) as client:
                rows = batch.run_batch(manifest, scheduler=client, progress=False)
        results[kind] = (folder, manifest, rows)
    return results


def test_every_good_job_finishes_and_the_bad_one_is_a_row(two_runs):
    for kind, (folder, _, rows) in two_runs.items():
        status = {r["name"]: r for r in rows}
        assert [r["name"] for r in rows][:2] == ["dqs-40", "dqs-80"]  # manifest order
        assert status["bad-file"]["status"] == "failed"
        assert "broken.glb" in status["bad-file"]["error"]
        assert all(r["status"] == "done" for n, r in status.items() if n != "bad-file"), kind
        assert not (folder / "out" / "bad.pc2").exists()
        metrics = json.loads((folder / "out" / "tracking2014-80.json").read_text())
        assert "tracking2014" in metrics["methods"]
        for method in ("ddm", "cor"):
            assert method in json.loads((folder / "out" / f"{method}.json").read_text())["methods"]


def test_the_pool_and_dask_write_identical_outputs(two_runs):
    pool, dask = outputs_of(two_runs["pool"][0]), outputs_of(two_runs["dask"][0])
    assert len(pool) == 11
    assert pool == dask


def test_a_rerun_skips_the_finished_jobs_and_redoes_a_changed_or_missing_one(two_runs):
    folder, manifest, _ = two_runs["pool"]
    os.remove(folder / "out" / "dqs-40.pc2")
    rows = {r["name"]: r["status"] for r in batch.run_batch(manifest, workers=2, progress=False)}
    assert rows["dqs-80"] == "skipped" and rows["tracking2014-40"] == "skipped"
    assert rows["dqs-40"] == "done"  # its output was missing
    assert rows["bad-file"] == "failed"
    doc = json.loads(manifest.read_text())
    doc["jobs"][1]["frames"] = 7  # a changed job has a new key
    manifest.write_text(json.dumps(doc))
    rows = {r["name"]: r["status"] for r in batch.run_batch(manifest, workers=2, progress=False)}
    assert rows["dqs-80"] == "done" and rows["dqs-40"] == "skipped"


def test_the_command_line_prints_the_summary_and_fails_on_a_failed_job(two_runs):
    folder, manifest, _ = two_runs["pool"]
    run = subprocess.run([sys.executable, "-m", "isokit.batch", str(manifest), "--no-progress"],
                         capture_output=True, text=True)
    assert run.returncode == 1
    assert "| bad-file | failed |" in run.stdout and "skipped (already done)" in run.stdout


def test_a_bad_manifest_is_a_one_line_error(tmp_path):
    path = tmp_path / "m.json"
    path.write_text(json.dumps({"format": "isokit-batch", "version": 1, "jobs": [{"method": "dqs"}]}))
    with pytest.raises(batch.ManifestError, match=r"jobs\[0\]: \"rig\" is missing"):
        batch.run_batch(path)
    run = subprocess.run([sys.executable, "-m", "isokit.batch", str(path)], capture_output=True, text=True)
    assert run.returncode == 2 and run.stderr.count("\n") == 1


def test_a_worker_with_another_isokit_version_fails_the_job(tmp_path):
    job = {"name": "x", "rig": "procedural:cylinder", "method": "dqs", "bends": ["Bone1:x:30"], "frames": 3,
           "outputs": {"pc2": str(tmp_path / "x.pc2")}}
    row = batch.run_job(job, "0.0.0-other")
    assert row["status"] == "failed" and "runs isokit" in row["error"] and "0.0.0-other" in row["error"]
    assert batch.run_job(job, batch._isokit_version())["status"] == "done"


def test_a_job_without_a_method_bakes_with_isokits_default(tmp_path):
    from isokit import skinning
    path = tmp_path / "m.json"
    path.write_text(json.dumps({"format": "isokit-batch", "version": 1, "jobs": [
        {"name": "x", "rig": "procedural:cylinder", "bends": ["Bone1:x:30"], "frames": 3,
         "outputs": {"pc2": "x.pc2"}}]}))
    jobs, _ = batch.load_manifest(str(path))
    assert jobs[0]["method"] == skinning.DEFAULT_METHOD == "implicit2013"
