"""The Coach view's speed chart: the car's speed round its lap against the limit lap's
target speed at the same places, start line on the left."""

from __future__ import annotations

from typing import TYPE_CHECKING

from racer_tui.app.widgets.chart import LineChart, Series

if TYPE_CHECKING:  # the coach's numpy and osqp load when a lap is coached, not with the app
    from sim.coach.lap_analysis import LapTrace


POINTS = 400  # along the lap: more than a chart cell can show at any width


class SpeedTraceChart(LineChart):
    """Two series over the lap's distance: the target (drawn under) and the car."""

    DEFAULT_CSS = """
    SpeedTraceChart { height: 1fr; min-height: 4; }
    SpeedTraceChart > .chart--primary { color: $secondary; }
    SpeedTraceChart > .chart--secondary { color: $accent; text-style: bold; }
    """

    def __init__(self, *, id: str | None = None) -> None:
        super().__init__("speed", unit=" m/s", id=id)
        self.series = [Series("target", "chart--primary"), Series("car", "chart--secondary")]

    def show(self, trace: LapTrace | None) -> None:
        if trace is None:
            speed, target = [], []
        else:
            car, limit = trace.resampled(POINTS)
            speed, target = car.tolist(), limit.tolist()
        self.series[0].values = target
        self.series[1].values = speed
        self._changed = True
        self.repaint_if_changed()

    def _title_text(self, width: int) -> str:
        wordings = (
            "speed round the lap, m/s: the car (bright) against the limit lap's target",
            "speed, m/s: the car (bright) against the target",
            "speed: car vs target",
        )
        return next((wording for wording in wordings if len(wording) <= width), wordings[-1])
