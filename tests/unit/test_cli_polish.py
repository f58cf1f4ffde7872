"""Issue 33, item 6: "did you mean", progress totals and status lines that keep the bar."""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from naoloc.app.cli import main
from naoloc.config import load_config
from naoloc.errors import ConfigError
from naoloc.viz.progress import Progress


def test_a_mistyped_verb_gets_a_suggestion(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main(["lokalize", "-c", "x"])
    assert info.value.code == 2
    assert "did you mean 'localize'?" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("data", "suggestion"),
    [
        ({"world": {"room": {"sise_m": [5]}}}, "room.sise_m: unknown key; did you mean 'size_m'?"),
        ({"survey": {"stepm": 0.2}}, "survey.stepm: unknown key; did you mean 'step_m'?"),
        ({"survy": {}}, "survy: unknown key; did you mean 'survey'?"),
    ],
)  # fmt: skip
def test_a_mistyped_config_key_gets_a_suggestion(data: dict[str, object], suggestion: str) -> None:
    with pytest.raises(ConfigError, match=suggestion.replace("?", r"\?")):
        load_config(data)


def test_nothing_close_suggests_nothing() -> None:
    with pytest.raises(ConfigError) as info:
        load_config({"survey": {"zzzz": 1}})
    assert str(info.value).endswith("survey.zzzz: unknown key")


def test_a_count_past_its_total_grows_the_total() -> None:
    stream = io.StringIO()
    with Progress(3, "survey", stream=stream, enabled=True) as bar:
        for _ in range(5):
            bar.update()
        assert bar.total == 5 and "5/5" in bar.line()
    assert "/3" not in stream.getvalue().rsplit("\r", 1)[-1]


def test_a_status_line_goes_above_the_bar_and_the_bar_is_redrawn() -> None:
    stream = io.StringIO()
    bar = Progress(None, "go-home poses", stream=stream, enabled=True)
    bar.update(1, "a very long note that the next shorter redraw must erase entirely")
    bar.note("lost: stopping to look")
    bar.update(1)
    text = stream.getvalue()
    status = "\r\x1b[Kgo-home poses: lost: stopping to look\n"
    assert status in text  # its own line, the bar's line erased first
    after = text.split(status, 1)[1]
    assert after.startswith("\r\x1b[Kgo-home poses 1")  # the bar drawn again below it
    assert all(chunk.startswith("\x1b[K") for chunk in text.split("\r")[1:])


def test_an_open_counter_without_steps_shows_no_count() -> None:
    bar = Progress(None, "localize", stream=io.StringIO(), enabled=True)
    assert bar.line().split()[:1] == ["localize"] and "0 " not in bar.line()


def test_at_is_echoed_in_both_frames() -> None:
    from naoloc.app.commands.localize import at_in_both_frames

    both = at_in_both_frames([2.0, 1.0, 0.0], {"origin_room_pose": [1.0, 1.0, 1.5707963]})
    assert both is not None and both["room"] == [2.0, 1.0, 0.0]
    assert both["map"] == pytest.approx([0.0, -1.0, -1.5708], abs=1e-4)
    assert at_in_both_frames([2.0, 1.0, 0.0], {}) == {"room": [2.0, 1.0, 0.0], "map": None}
    assert at_in_both_frames(None, {}) is None


def test_make_demo_installs_only_the_sim_extra() -> None:
    makefile = (Path(__file__).resolve().parents[2] / "Makefile").read_text(encoding="utf-8")
    demo = makefile.split("\ndemo:", 1)[1].split("\n\n", 1)[0]
    assert "DEMO_STAMP" in demo and "venv" not in demo.split("\n", 1)[0].replace("$(VENV)", "")
    stamp = makefile.split("$(DEMO_STAMP):", 1)[1].split("\n\n", 1)[0]
    assert '-e ".[sim]"' in stamp
