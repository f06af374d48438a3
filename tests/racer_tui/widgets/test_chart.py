"""Training charts: running means, calm repaints, readable axes."""

from __future__ import annotations

import pytest
from textual.app import App, ComposeResult

from racer_tui.app.widgets.chart import LineChart, format_value, running_mean


def test_running_mean_averages_the_last_window_values() -> None:
    assert running_mean([2.0, 4.0, 6.0, 8.0], 2) == pytest.approx([2.0, 3.0, 5.0, 7.0])
    assert running_mean([], 5) == []


def test_values_are_formatted_for_a_narrow_axis() -> None:
    assert format_value(1234.5) == "1234"
    assert format_value(21_812.0) == "21.8k"
    assert format_value(432_512.0) == "433k"
    assert format_value(-12_500_000.0) == "-12.5M"
    assert format_value(0.0) == "0" and format_value(0.004) == "0.004"
    assert format_value(12.345) == "12.3"
    assert format_value(0.01234) == "0.012"
    assert format_value(float("nan")) == "-"


class ChartApp(App[None]):
    def compose(self) -> ComposeResult:
        yield LineChart("reward", mean_window=10, refresh_hz=1000.0)


async def test_a_burst_of_data_repaints_once_per_tick_not_per_value() -> None:
    app = ChartApp()
    async with app.run_test(size=(60, 12)) as pilot:
        chart = app.query_one(LineChart)
        await pilot.pause()
        chart.set_interval(3600, lambda: None)  # keep the app alive; repaint manually below
        repaints = chart.repaints
        for value in range(500):
            chart.extend([float(value)])
        chart.repaint_if_changed()
        await pilot.pause()
        assert chart.repaints - repaints <= 1
        lines = [chart.render_line(y).text for y in range(chart.size.height)]
        assert lines[0].startswith("reward: 499")
        assert "mean of 10: 494" in lines[0]
        assert any("499" in line and "┤" in line for line in lines[1:])
        assert any(any("⠁" <= ch <= "⣿" for ch in line) for line in lines[1:])


@pytest.mark.parametrize(
    ("width", "title"),
    [(28, "(mean 494)"), (16, "reward: 499 ~494"), (15, "reward 499 ~494"), (12, "reward: 499")],
)
async def test_a_narrow_chart_shortens_its_title_mean_first(width: int, title: str) -> None:
    """The mean gives way before the title or the latest value is cut (a chart at 60x20
    has 18 columns: 'progress: 100 % ~98.4' was shown as 'progress: 100 % ~9')."""
    app = ChartApp()
    async with app.run_test(size=(width, 8)) as pilot:
        chart = app.query_one(LineChart)
        chart.extend([float(value) for value in range(500)])
        chart.repaint_if_changed()
        await pilot.pause()
        first = chart.render_line(0).text
        assert title in first and len(first.rstrip()) <= width
