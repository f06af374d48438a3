// The live page: fills itself from the server's event stream (/api/live/stream). Every
// value is set as text (textContent), never as markup: names come from racers' machines.
"use strict";

function text(id, value) {
  const element = document.getElementById(id);
  if (element !== null) {
    element.textContent = value;
  }
}

function seconds(value) {
  return value === null || value === undefined ? "-" : value.toFixed(3);
}

function clock(value) {
  const minutes = Math.floor(value / 60);
  const rest = (value - minutes * 60).toFixed(1).padStart(4, "0");
  return minutes + ":" + rest;
}

function showLaps(laps) {
  const body = document.getElementById("laps");
  if (body === null) {
    return;
  }
  const rows = laps.map((lap, index) => {
    const row = document.createElement("tr");
    const cells = [
      String(index + 1),
      seconds(lap.time_seconds),
      lap.penalty_seconds ? lap.penalty_seconds.toFixed(0) : "",
      String(lap.offtracks),
      lap.counts ? "yes" : "no",
    ];
    cells.forEach((value, column) => {
      const cell = document.createElement("td");
      cell.textContent = value;
      if (column < 4) {
        cell.className = "num";
      }
      row.appendChild(cell);
    });
    return row;
  });
  body.replaceChildren(...rows);
}

function show(live) {
  const heat = live.heat;
  document.body.dataset.state = heat ? heat.state : "none";
  text("racer", heat ? heat.racer : "No heat running");
  text("car", heat ? heat.car : "");
  text("state", heat ? heat.state : "waiting for the next heat");
  text("time-left", heat ? clock(heat.time_left) : "-");
  text("lap", heat ? String(heat.lap) : "-");
  text("lap-time", heat ? heat.lap_time.toFixed(1) : "-");
  text("best-lap", heat ? seconds(heat.best_lap) : "-");
  text("offtracks", heat ? heat.offtracks + (heat.limit === null ? "" : " of " + heat.limit) : "-");
  const gap = live.gap_to_leader;
  text("gap", gap === null ? "-" : (gap > 0 ? "+" : "") + gap.toFixed(3));
  text("leader", live.leader ? live.leader.racer + "  " + seconds(live.leader.score) : "-");
  showLaps(heat ? heat.laps : []);
  // The overlay's card at the end of a heat (elements the live page does not have).
  text("card-racer", heat ? heat.racer : "");
  text("card-best", heat ? seconds(heat.best_lap) : "");
  text("card-place", gap === null ? "" : gap <= 0 ? "leads the night" : "behind the leader");
  const dot = document.getElementById("car-dot");
  if (dot !== null) {
    const place = heat ? heat.car_on_map : null;
    dot.setAttribute("cx", place ? String(place[0]) : "-100");
    dot.setAttribute("cy", place ? String(place[1]) : "-100");
  }
}

const now = document.getElementById("live-now");
if (now !== null) {
  show(JSON.parse(now.textContent));
}
const stream = new EventSource("/api/live/stream" + window.location.search);
stream.onmessage = (event) => show(JSON.parse(event.data));
stream.onerror = () => text("state", "reconnecting…");
