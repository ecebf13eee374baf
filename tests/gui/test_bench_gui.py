"""The GUI benchmark's measurements (bench/bench_gui.py) on short spans, offscreen: what they
drive and what they return, never how fast it is."""

from bench import bench_gui


def test_frame_rates_and_first_frames_are_measured_as_many_times():
    rates, slowest = bench_gui.frame_rates(2000, repeat=2, seconds=0.2)
    assert len(rates) == 2 and min(rates) > 0 and slowest > 0
    imports, first = bench_gui.first_frames(2000, repeat=1)  # a fresh process
    assert len(imports) == len(first) == 1 and min(imports + first) > 0


def test_a_stall_session_idles_then_makes_two_runs_each_analysed_in_the_same_window():
    measured = bench_gui.stall_session(runs=2, duration=0.5, idle_s=0.2)
    assert measured["idle"] >= 0
    assert [sorted(run) for run in measured["runs"]] == [["acquire", "end", "status"]] * 2
    for run in measured["runs"]:
        assert run["status"] == "completed"
        assert run["acquire"] >= 0 and run["end"] >= 0
