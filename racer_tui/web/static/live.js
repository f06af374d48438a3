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

function showMatch(match) {
  const list = document.getElementById("match-cars");
  if (list === null) {
    return;
  }
  const names = match.cars.map((car) => car.racer);
  const ordered = match.cars
    .map((car, grid) => ({ car, grid }))
    .sort((a, b) => a.car.place - b.car.place);
  const items = ordered.map(({ car, grid }) => {
    const item = document.createElement("li");
    const swatch = document.createElement("span");
    swatch.className = "swatch grid-" + grid;
    item.appendChild(swatch);
    const laps = match.lap_count === null ? car.laps : car.laps + "/" + match.lap_count;
    const gap = car.place > 1 && car.gap !== null ? "  +" + car.gap.toFixed(2) + " s" : "";
    const held = car.held_for ? "  " + car.held_for : "";
    const won = match.state === "over" && car.place === 1 ? "  won" : "";
    item.appendChild(document.createTextNode(car.place + " " + car.racer + "  laps " + laps + gap + held + won));
    return item;
  });
  list.replaceChildren(...items);
  text("match-title", match.title + " (" + match.match_id + ")");
  text("match-clock", clock(match.clock));
  const newest = match.incidents.length ? match.incidents[match.incidents.length - 1] : null;
  text(
    "match-news",
    newest === null
      ? ""
      : newest.kind === "crash"
        ? names[newest.car] + " ran into " + names[newest.other] + " and is held"
        : names[newest.car] + " passed " + names[newest.other],
  );
}

function showMatchCars(match) {
  for (let k = 0; k < 6; k += 1) {
    const dot = document.getElementById("match-car-" + k);
    if (dot === null) {
      continue;
    }
    const car = match && k < match.cars.length ? match.cars[k] : null;
    const place = car ? car.on_map : null;
    dot.setAttribute("cx", place ? String(place[0]) : "-100");
    dot.setAttribute("cy", place ? String(place[1]) : "-100");
  }
}

function show(live) {
  const match = live.match;
  showMatchCars(match);
  if (match) {
    document.body.dataset.state = "match";
    text("racer", match.cars.map((car) => car.racer).join(" v "));
    text("car", match.title);
    showMatch(match);
    const dot = document.getElementById("car-dot");
    if (dot !== null) {
      dot.setAttribute("cx", "-100");
    }
    return;
  }
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
