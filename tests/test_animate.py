"""Plan animations (GIF / MP4 through imageio) and Gymnasium's RecordVideo on rgb_array."""

from __future__ import annotations

import gymnasium as gym
import imageio.v3 as iio
import numpy as np
import pytest
import sixaxis_avoid
from sixaxis_avoid import animate


def test_frames_follow_the_plan(paper_simple_plan):
    frames = animate.plan_frames(paper_simple_plan, "paper_simple", frames_per_move=4, size=200)
    moves = len(paper_simple_plan.path) - 1
    assert len(frames) == 1 + 4 * moves + 6  # start, 4 per move, last pose held
    assert all(f.dtype == np.uint8 and f.shape == frames[0].shape for f in frames)
    assert not np.array_equal(frames[0], frames[4])  # the arm moved
    np.testing.assert_array_equal(frames[-1], frames[-2])


def test_frames_draw_the_plans_boxes():
    """A physical world's plan: its ``obstacle_boxes_mm`` are drawn; a plan JSON without the
    key (older files) falls back to the scenario's boxes."""
    s = sixaxis_avoid.Scenario("paper_simple").regrid(50)
    plan = sixaxis_avoid.plan(s, seed=0, initial_q="distance")
    kw = {"frames_per_move": 1, "size": 200, "hold_frames": 0}
    boxed = animate.plan_frames(plan, s, **kw)
    d = plan.to_dict()
    d.pop("obstacle_boxes_mm")
    np.testing.assert_array_equal(animate.plan_frames(d, s, **kw)[0], boxed[0])
    d["obstacle_boxes_mm"] = []
    free = animate.plan_frames(d, s, **kw)
    assert np.any(free[0] != boxed[0], axis=-1).sum() > 0.05 * free[0].shape[0] * free[0].shape[1]


def test_gif_and_mp4_are_written_and_readable(paper_simple_plan, tmp_path):
    gif = animate.animate_plan(
        paper_simple_plan, tmp_path / "a.gif", "paper_simple", frames_per_move=3
    )
    back = iio.imread(gif, index=None)
    # Pillow merges the identical held frames into one longer frame.
    assert back.shape[0] >= 1 + 3 * (len(paper_simple_plan.path) - 1)
    mp4 = animate.animate_plan(
        paper_simple_plan, tmp_path / "a.mp4", "paper_simple", frames_per_move=3
    )
    assert mp4.stat().st_size > 1000
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.gif", "a.mp4"]  # no temp files
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="path"):
        animate.write_frames([np.zeros((8, 8, 3), np.uint8)], tmp_path / "a.avi")


def test_cli_from_a_plan_json(paper_simple_plan, tmp_path):
    plan_json = tmp_path / "plan.json"
    plan_json.write_text(paper_simple_plan.to_json())
    out = tmp_path / "p.gif"
    rc = animate.main(
        ["--plan", str(plan_json), "--scenario", "paper_simple", "--out", str(out), "--size", "160"]
    )
    assert rc == 0 and out.stat().st_size > 0


def test_record_video_on_rgb_array(tmp_path):
    # RecordVideo writes through moviepy (in the video extra).
    env = gym.wrappers.RecordVideo(
        gym.make(sixaxis_avoid.ENV_ID, render_mode="rgb_array", render_size=128),
        str(tmp_path / "videos"),
        episode_trigger=lambda ep: True,
        disable_logger=True,
    )
    env.reset(seed=0)
    for a in (5, 5, 3, 2, 1):
        env.step(a)
    env.close()
    videos = list((tmp_path / "videos").glob("*.mp4"))
    assert len(videos) == 1 and videos[0].stat().st_size > 0
    assert iio.imread(videos[0], index=None, plugin="FFMPEG").shape[0] >= 5
