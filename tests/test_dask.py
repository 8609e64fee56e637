"""The same batch on a Dask LocalCluster (issue 18); skipped without the extra."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("dask.distributed")

from motiondetect.app.runner import run  # noqa: E402
from motiondetect.app.settings import make_settings  # noqa: E402

from .cli_outputs import noise_video  # noqa: E402

OUTPUTS = ("frames.jsonl", "detections.csv", "events.csv")


def batch(tmp_path: Path) -> Path:
    folder = tmp_path / "batch"
    folder.mkdir()
    for i in range(4):
        noise_video(folder / f"v{i}.mp4", frames=12, seed=i)
    return folder


@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # distributed's own, at shutdown
@pytest.mark.filterwarnings("ignore::ResourceWarning")
def test_a_local_cluster_gives_the_same_outputs_as_one_job(tmp_path):
    folder = batch(tmp_path)
    (folder / "corrupt.mp4").write_bytes((folder / "v0.mp4").read_bytes()[:400])
    one = make_settings({"output": tmp_path / "one", "video": False, "jobs": 1})
    dask = make_settings(
        {"output": tmp_path / "dask", "video": False, "jobs": 2, "scheduler": "local"}
    )
    first, distributed = run([folder], one), run([folder], dask)
    assert [(r.job.name, r.status) for r in distributed.results] == [
        (r.job.name, r.status) for r in first.results
    ]
    assert [r.job.name for r in distributed.failed] == ["corrupt"]
    for i in range(4):
        for name in OUTPUTS:
            a = (tmp_path / "one" / f"v{i}" / name).read_text()
            assert (tmp_path / "dask" / f"v{i}" / name).read_text() == a
    again = run([folder], dask)
    assert {r.status for r in again.results if r.job.name != "corrupt"} == {"skipped"}
