"""tracks.csv: one row per tracked object, summed from the per-frame detections."""

from __future__ import annotations

import csv
import io

from motiondetect.detection.track_table import TrackTable
from motiondetect.io.report import TRACK_COLUMNS, write_tracks_csv


def detection(track, bbox, score, detectors=("velocity-ray",)) -> dict:
    return {"track": track, "bbox": list(bbox), "score": score, "detectors": list(detectors)}


def test_each_track_is_summed_with_exact_answers():
    table = TrackTable()
    table.add(0, 0.0, [detection(None, (0, 0, 5, 5), 0.9)])  # no track: not counted
    table.add(3, 0.1, [detection(7, (10, 20, 4, 6), 0.5)])
    table.add(4, 0.2, [detection(7, (14, 18, 4, 6), 0.8, ("velocity-animate",))])
    table.add(4, 0.2, [detection(2, (50, 50, 10, 10), 0.3)])
    table.add(6, 0.3, [detection(7, (20, 22, 6, 6), 0.6)])
    assert len(table) == 2
    first, second = table.rows()
    # By first frame: track 7 (frame 3) before track 2 (frame 4).
    assert first["track"] == 7 and second["track"] == 2
    assert (first["start_frame"], first["end_frame"], first["frames"]) == (3, 6, 3)
    assert (first["start_s"], first["end_s"]) == (0.1, 0.3)
    assert first["duration_s"] == 0.3 - 0.1
    assert (first["peak_frame"], first["peak_score"]) == (4, 0.8)
    assert first["detectors"] == ["velocity-animate", "velocity-ray"]
    assert (first["start_cx"], first["start_cy"], first["end_cx"], first["end_cy"]) == (
        12.0, 23.0, 23.0, 25.0,
    )  # fmt: skip
    assert first["bbox"] == [10, 18, 16, 10]  # x 10..26, y 18..28
    assert (second["start_frame"], second["end_frame"], second["frames"]) == (4, 4, 1)
    assert second["bbox"] == [50, 50, 10, 10]


def test_tracks_csv_has_the_columns_and_one_row_per_track():
    table = TrackTable()
    table.add(1, 1 / 30, [detection(1, (2, 4, 6, 8), 0.25)])
    table.add(2, 2 / 30, [detection(1, (4, 4, 6, 8), 0.5)])
    fp = io.StringIO()
    write_tracks_csv(fp, table.rows())
    rows = list(csv.reader(fp.getvalue().splitlines()))
    assert rows[0] == TRACK_COLUMNS
    assert rows[1] == [
        "1", "1", "2", "0.0333", "0.0667", "00:00:00.033", "00:00:00.067", "0.0333", "2", "2",
        "0.5000", "velocity-ray", "5.0", "8.0", "7.0", "8.0", "2", "4", "8", "8", "", "",
    ]  # fmt: skip


def test_no_tracks_gives_the_header_alone():
    fp = io.StringIO()
    write_tracks_csv(fp, TrackTable().rows())
    assert fp.getvalue().splitlines() == [",".join(TRACK_COLUMNS)]


def test_a_tracks_own_velocity_is_the_mean_of_its_found_frames():
    """(30, -10) and (50, 0) px/s on the frames it was found, then held with
    its last repeated: the mean of the two found, (40, -5); in tracks.csv's
    last two columns."""
    table = TrackTable()
    for frame, own, held in (
        (1, (30.0, -10.0), False), (2, (50.0, 0.0), False), (3, (50.0, 0.0), True),
    ):  # fmt: skip
        found = detection(5, (10, 10, 4, 4), 0.5) | {"own_velocity_px_s": list(own)}
        table.add(frame, frame / 30, [found | {"held": True} if held else found])
    (row,) = table.rows()
    assert (row["own_vx_px_s"], row["own_vy_px_s"]) == (40.0, -5.0)
    fp = io.StringIO()
    write_tracks_csv(fp, table.rows())
    assert list(csv.reader(fp.getvalue().splitlines()))[1][-2:] == ["40.0", "-5.0"]
