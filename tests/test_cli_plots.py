"""The command line for a newcomer (issue 27):

- `artibus --help` lists every verb, each on one line of its summary;
- `artibus plot RESULTS.csv SIGNAL...` draws the signals of a results file, a panel per
  unit with the unit from the results' units file; an unknown signal is an error naming
  it and the closest names, nothing written;
- `artibus can plot LOG --signal ...` draws a CAN log's frame timing (the time between
  a message's frames is its 10 ms cycle, within the arbitration's 0.1 ms) and decoded signals;
- no file the user did not name: `bode` writes its CSV only with -o (phase in deg, as
  its plot); `calibrate -o` must name a parameter set, checked before any run;
- the bench index links the demo, and every bench of the index has its thumbnail, with
  the report written under a relative directory as ./run.sh writes it;
- the bird's-eye animation is at least 800 px wide."""
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from artibus import runner
from artibus.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[1]


def artibus(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "artibus", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=600)


def test_help_lists_every_verb_on_one_line():
    p = artibus("--help")
    assert p.returncode == 0
    summary = p.stdout.split("Throughout:")[0]
    parser = build_parser()
    verbs = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction").choices
    for verb, sub in verbs.items():
        lines = [ln for ln in summary.splitlines() if re.match(rf"\s+artibus {verb}\b", ln)]
        assert lines, f"artibus --help: no line for {verb}"
        if verb == "can":
            subs = next(a for a in sub._actions if a.__class__.__name__ == "_SubParsersAction").choices
            for w in subs:
                assert any(re.match(rf"\s+artibus can {w}\b", ln) for ln in lines), f"no line for can {w}"
    assert "(for now)" not in summary and "main job" not in summary


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    d = tmp_path_factory.mktemp("plot")
    r = runner.run("Scania18m_LaneChange", stop_time=2.0, record=["Bus.artAngle[1]", "Bus.r[1]", "Bus.r[2]",
                                                                 "Bus.FjointY[1]"])
    return runner.save(r, d / "lc.csv"), r


def test_plot_draws_the_signals_a_panel_per_unit(results, tmp_path):
    csv, r = results
    out = tmp_path / "p.png"
    p = artibus("plot", csv, "Bus.r[*]", "Bus.artAngle[1]", "-o", out)
    assert p.returncode == 0, p.stderr
    assert "3 signals (Bus.r[1], Bus.r[2], Bus.artAngle[1])" in p.stdout
    with Image.open(out) as im:
        # two units (rad/s, rad): two panels of 2.4 in (and 0.3 in for the title) at 110 dpi, a figure
        # 11 in wide (the legends beside the panels: artibus.report.plots.signals)
        assert im.width == round(11 * 110) and abs(im.height - (2 * 2.4 + 0.3) * 110) < 3
    from artibus.report import quick
    names, cols, units = quick.read_results_csv(csv)
    assert units["Bus.r[1]"] == r.units["Bus.r[1]"] == "rad/s" and units["Bus.artAngle[1]"] == "rad"
    assert np.allclose(cols["Bus.r[2]"], np.asarray(r["Bus.r[2]"]), rtol=1e-6, atol=1e-12)
    panels = quick._panels({n: cols[n] for n in ("Bus.r[1]", "Bus.artAngle[1]", "Bus.r[2]")}, units)
    assert [(lab, list(s)) for lab, s in panels] == [("[rad/s]", ["Bus.r[1]", "Bus.r[2]"]),
                                                     ("[rad]", ["Bus.artAngle[1]"])]


def test_plot_unknown_signal_is_an_error_naming_it(results, tmp_path):
    csv, _ = results
    out = tmp_path / "none.png"
    p = artibus("plot", csv, "Bus.artangle[1]", "-o", out)
    assert p.returncode == 1 and "no signal 'Bus.artangle[1]'" in p.stderr and "Bus.artAngle[1]" in p.stderr
    assert "Traceback" not in p.stderr and not out.exists()


@pytest.fixture(scope="module")
def can_log(tmp_path_factory):
    d = tmp_path_factory.mktemp("can")
    log = d / "run.blf"
    p = artibus("run", "Bus36m_Circle_CAN", "--stop-time", "1", "--can-log", log, "-o", d / "can.csv")
    assert p.returncode == 0, p.stderr
    return log


def test_can_plot_timing_and_signals(can_log, tmp_path):
    from artibus.report import quick
    out = tmp_path / "can.png"
    png, chosen, known = quick.can_plot(can_log, ["RoadWheelAngleA1"], out=out)
    assert png == out and out.is_file()
    assert len(chosen) == 1 and chosen[0].endswith(".RoadWheelAngleA1") and chosen[0] in known
    # the frame timing it draws: every message of the 10 ms network every 10 ms
    from artibus.can import read_log
    by_id = {}
    for f in read_log(can_log):
        by_id.setdefault(f.arbitration_id, []).append(f.timestamp)
    assert by_id and all(np.allclose(np.diff(ts), 0.010, atol=1e-4) for ts in by_id.values())
    p = artibus("can", "plot", can_log, "-o", tmp_path / "timing.png")
    assert p.returncode == 0, p.stderr
    assert "the frames' timing" in p.stdout and "--signal NAME adds a decoded signal" in p.stdout
    p = artibus("can", "plot", can_log, "--signal", "NoSuchSignal", "-o", tmp_path / "x.png")
    assert p.returncode == 1 and "no signal" in p.stderr and not (tmp_path / "x.png").exists()


def test_bode_writes_its_csv_only_when_asked(tmp_path):
    base = ["bode", "MultiAxle_StepSteer", "--input", "Steering.delta1", "--measure", "Vehicle.w_r",
            "--set", "Steering.delta1=0", "--fmin", "0.5", "--n", "1", "--periods", "2"]
    p = artibus(*base, cwd=tmp_path)
    assert p.returncode == 1 and "-o FILE.csv" in p.stderr
    p = artibus(*base, "--plot", "b.png", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert sorted(x.name for x in tmp_path.iterdir()) == ["b.png"]
    p = artibus(*base, "-o", "b.csv", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    header = (tmp_path / "b.csv").read_text().splitlines()[0]
    assert "Vehicle.w_r phase [deg]" in header


def test_calibrate_output_must_be_a_parameter_set(tmp_path):
    p = artibus("calibrate", "-o", tmp_path / "gains.txt")
    assert p.returncode == 1 and "FILE.ssv" in p.stderr and not (tmp_path / "gains.txt").exists()


def test_index_links_the_demo_and_has_a_thumbnail_per_bench(tmp_path):
    """As ./run.sh: the demo into out/demo, then benches with --report out (relative)."""
    assert main(["demo", "--report", str(tmp_path / "out" / "demo")]) == 0   # absolute is fine for the demo
    import os
    from artibus.report.runs import run_benches
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        summary = run_benches(["Urbino18_Circle", "MultiAxle_StepSteer"], every=True, report="out",
                              log=lambda *a: None)
    finally:
        os.chdir(cwd)
    index = (tmp_path / "out" / "index.html").read_text()
    assert 'href="demo/index.html"' in index
    for name, d, _ in summary:
        assert (tmp_path / "out" / name / "thumb.png").is_file(), name
        assert f'src="{name}/thumb.png"' in index
    demo = (tmp_path / "out" / "demo" / "index.html").read_text()
    for src in re.findall(r'(?:src|href)="([^"]+)"', demo):
        assert (tmp_path / "out" / "demo" / src).exists(), src


def test_animation_is_at_least_800_px_wide(tmp_path):
    from artibus.report.animation import bench_animation
    r = runner.run("Urbino18_Circle", stop_time=10.0)
    [(name, _)] = bench_animation(r, tmp_path, title="Urbino18_Circle", frames=10)
    f = tmp_path / name
    if f.suffix == ".gif":
        with Image.open(f) as im:
            assert im.width >= 800 and im.n_frames == 10
    else:       # MP4 (ffmpeg installed): its width from ffprobe
        w = subprocess.run(["ffprobe", "-v", "error", "-select_streams", "v:0", "-show_entries", "stream=width",
                            "-of", "csv=p=0", str(f)], capture_output=True, text=True).stdout.strip()
        assert int(w) >= 800


def test_the_main_jobs_output(tmp_path):
    """out/ as ./run.sh leaves it: a thumbnail on the index for every bench, the demo linked,
    every animation at least 800 px wide, and artibus plot works on a bench's results."""
    out = ROOT / "out"
    if not (out / "index.html").is_file():
        pytest.skip("no out/index.html: run ./run.sh first")
    from artibus.bench import ssp
    index = (out / "index.html").read_text()
    for name in ssp.bench_names():
        if (out / name / "index.html").is_file():
            assert f'src="{name}/thumb.png"' in index and (out / name / "thumb.png").is_file(), name
    assert 'href="demo/index.html"' in index and (out / "demo" / "index.html").is_file()
    for f in out.glob("*/birds_eye.gif"):
        with Image.open(f) as im:
            assert im.width >= 800, f
    results = out / "Bus36m_Circle" / "results.csv"
    if results.is_file():
        p = artibus("plot", results, "Bus.artAngle[*]", "-o", tmp_path / "a.png")
        assert p.returncode == 0 and (tmp_path / "a.png").is_file(), p.stderr
