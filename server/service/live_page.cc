#include "server/service/live_page.h"

namespace localizer::server {
namespace {

// Kept as one readable document; the drawing code is plain DOM + SVG (no libraries).
constexpr std::string_view kPage = R"html(<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>localizer: live sessions</title>
<style>
  body { font: 14px system-ui, sans-serif; margin: 16px; color: #222; background: #fff; }
  h1 { font-size: 20px; margin: 0 0 4px; }
  #status { color: #666; margin-bottom: 4px; }
  .legend { color: #444; margin-bottom: 12px; }
  .session { border: 1px solid #ccc; border-radius: 6px; padding: 8px 12px; margin-bottom: 14px; }
  .session h2 { font-size: 16px; margin: 0 0 4px; }
  .session.finished { border-style: dashed; background: #fafafa; }
  .session.finished h2 { color: #555; }
  button.replay { font-size: 12px; margin-left: 8px; }
  h3.finished-title { font-size: 15px; margin: 18px 0 8px; color: #444; }
  .meta { color: #444; font-family: ui-monospace, monospace; font-size: 12px; margin-bottom: 6px; }
  .panels { display: flex; flex-wrap: wrap; gap: 10px; }
  svg.plot { width: 520px; height: 400px; border: 1px solid #eee; background: #fcfcfc; }
  svg .grid { stroke: #e4e4e4; stroke-width: 1; }
  svg .frame { stroke: #999; fill: none; }
  svg text { font: 11px system-ui, sans-serif; fill: #555; }
  svg text.title { font-size: 13px; fill: #222; }
  svg .sensor { fill: #1f77b4; }
  svg .track { stroke: #d62728; stroke-width: 2; fill: none; stroke-linejoin: round; }
  svg .latest { fill: #d62728; stroke: #fff; stroke-width: 1.5; }
  svg .target rect { fill: #2ca02c; } svg .target.tentative rect { fill: #bbb; }
  svg .target.coasting rect { fill: #ff7f0e; } svg .target text { font-size: 10px; }
  svg .latest.silent { fill: #fff; stroke: #d62728; stroke-width: 2; }
  .presence { display: inline-block; border-radius: 3px; padding: 0 5px; margin-right: 6px;
              font-family: ui-monospace, monospace; font-size: 12px; color: #fff; }
  .presence.present { background: #2ca02c; } .presence.silent { background: #888; }
  .presence.untested { background: #ccc; color: #333; }
  .presence.ambiguous { background: #ff7f0e; }
  .presence.far { background: #9467bd; }
</style>
</head>
<body>
<h1>localizer: live sessions</h1>
<div id="status">loading /sessions ...</div>
<div class="legend"><span style="color:#1f77b4">&#9679;</span> sensor &nbsp;
  <span style="color:#d62728">&#9473;</span> estimated track (last fixes) &nbsp;
  <span style="color:#d62728">&#9679;</span> latest estimate (&#9675; hollow: no source heard, a prediction) &nbsp;
  <span style="color:#2ca02c">&#9632;</span> target track (detection sessions) &nbsp; axes in metres;
  direction sessions: each source's azimuth over time and its direction now, one colour per id (hollow: not heard)</div>
<div id="sessions"></div>
<h3 class="finished-title" id="finished-title" hidden>Ended sessions (kept for a while: --live-keep-finished)</h3>
<div id="finished"></div>
<p><a href="/metrics">/metrics</a> (Prometheus) &middot; <a href="/sessions">/sessions</a> (JSON)</p>
<script>
"use strict";
const SVG_NS = "http://www.w3.org/2000/svg";
const W = 520, H = 400, LEFT = 56, RIGHT = 14, TOP = 26, BOTTOM = 40;

function el(tag, attrs, parent, text) {
  const e = tag.startsWith("svg:") ? document.createElementNS(SVG_NS, tag.slice(4)) : document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  if (parent) parent.appendChild(e);
  return e;
}

// A round tick step (1, 2 or 5 times a power of ten) giving about eight ticks over `span`.
function tickStep(span) {
  const raw = span / 8, p = Math.pow(10, Math.floor(Math.log10(raw)));
  for (const m of [1, 2, 5, 10]) if (m * p >= raw) return m * p;
  return 10 * p;
}

function fmt(v) { return Math.abs(v) < 1e-9 ? "0" : Number(v.toPrecision(4)).toString(); }

// One panel: axes a and b (0 x, 1 y, 2 z) of the sensors and the track, equal scale in metres.
function drawPanel(svg, title, a, b, sensors, track, targets, silent) {
  while (svg.firstChild) svg.removeChild(svg.firstChild);
  const names = ["x", "y", "z"];
  const pts = sensors.concat(track.map(p => p.position_m), targets.map(t => t.position_m))
      .filter(p => p && p[a] !== null && p[b] !== null);
  let minA = Infinity, maxA = -Infinity, minB = Infinity, maxB = -Infinity;
  for (const p of pts) {
    minA = Math.min(minA, p[a]); maxA = Math.max(maxA, p[a]);
    minB = Math.min(minB, p[b]); maxB = Math.max(maxB, p[b]);
  }
  if (!pts.length) { minA = minB = -1; maxA = maxB = 1; }
  const span = Math.max(maxA - minA, maxB - minB, 1.0) * 1.15;
  const plotW = W - LEFT - RIGHT, plotH = H - TOP - BOTTOM;
  const scale = Math.min(plotW / span, plotH / span);  // pixels per metre, same on both axes
  const cA = (minA + maxA) / 2, cB = (minB + maxB) / 2;
  const X = v => LEFT + plotW / 2 + (v - cA) * scale;
  const Y = v => TOP + plotH / 2 - (v - cB) * scale;
  const a0 = cA - plotW / 2 / scale, a1 = cA + plotW / 2 / scale;
  const b0 = cB - plotH / 2 / scale, b1 = cB + plotH / 2 / scale;
  const step = tickStep(Math.max(a1 - a0, b1 - b0));
  for (let v = Math.ceil(a0 / step) * step; v <= a1; v += step) {
    el("svg:line", {class: "grid", x1: X(v), x2: X(v), y1: TOP, y2: TOP + plotH}, svg);
    el("svg:text", {x: X(v), y: TOP + plotH + 14, "text-anchor": "middle"}, svg, fmt(v));
  }
  for (let v = Math.ceil(b0 / step) * step; v <= b1; v += step) {
    el("svg:line", {class: "grid", x1: LEFT, x2: LEFT + plotW, y1: Y(v), y2: Y(v)}, svg);
    el("svg:text", {x: LEFT - 5, y: Y(v) + 4, "text-anchor": "end"}, svg, fmt(v));
  }
  el("svg:rect", {class: "frame", x: LEFT, y: TOP, width: plotW, height: plotH}, svg);
  el("svg:text", {class: "title", x: LEFT, y: 17}, svg, title);
  el("svg:text", {x: LEFT + plotW / 2, y: H - 6, "text-anchor": "middle"}, svg, names[a] + " (m)");
  el("svg:text", {x: 14, y: TOP + plotH / 2, "text-anchor": "middle",
                  transform: `rotate(-90 14 ${TOP + plotH / 2})`}, svg, names[b] + " (m)");
  sensors.forEach((p, i) => {
    const c = el("svg:circle", {class: "sensor", cx: X(p[a]), cy: Y(p[b]), r: 5}, svg);
    el("svg:title", {}, c, `sensor ${i}: (${p.map(fmt).join(", ")}) m`);
  });
  const line = track.filter(p => p.position_m[a] !== null && p.position_m[b] !== null);
  if (line.length) {
    el("svg:polyline", {class: "track", "data-points": line.length,
                        points: line.map(p => `${X(p.position_m[a]).toFixed(1)},${Y(p.position_m[b]).toFixed(1)}`).join(" ")}, svg);
    const last = line[line.length - 1].position_m;
    el("svg:circle", {class: silent ? "latest silent" : "latest", cx: X(last[a]), cy: Y(last[b]), r: 6}, svg);
  }
  // Detection sessions: each target track after the latest scan, labelled with its id.
  targets.filter(t => t.position_m[a] !== null && t.position_m[b] !== null).forEach(t => {
    const g = el("svg:g", {class: "target " + t.status}, svg);
    el("svg:rect", {x: X(t.position_m[a]) - 4, y: Y(t.position_m[b]) - 4, width: 8, height: 8}, g);
    el("svg:text", {x: X(t.position_m[a]) + 6, y: Y(t.position_m[b]) - 6}, g, String(t.id));
    el("svg:title", {}, g, `track ${t.id} (${t.status}): (${t.position_m.map(fmt).join(", ")}) m`);
  });
}

// Direction sessions: one colour per source id.
const PALETTE = ["#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf"];
const colourOf = id => PALETTE[(id - 1) % PALETTE.length];
const DEG = 180 / Math.PI;

// Axes of a plot in data units: x over [x0, x1], y over [y0, y1], ticks every xs / ys.
function axes(svg, title, xName, yName, x0, x1, y0, y1, xs, ys) {
  while (svg.firstChild) svg.removeChild(svg.firstChild);
  const plotW = W - LEFT - RIGHT, plotH = H - TOP - BOTTOM;
  const X = v => LEFT + (v - x0) / (x1 - x0) * plotW, Y = v => TOP + plotH - (v - y0) / (y1 - y0) * plotH;
  for (let v = Math.ceil(x0 / xs) * xs; v <= x1; v += xs) {
    el("svg:line", {class: "grid", x1: X(v), x2: X(v), y1: TOP, y2: TOP + plotH}, svg);
    el("svg:text", {x: X(v), y: TOP + plotH + 14, "text-anchor": "middle"}, svg, fmt(v));
  }
  for (let v = Math.ceil(y0 / ys) * ys; v <= y1; v += ys) {
    el("svg:line", {class: "grid", x1: LEFT, x2: LEFT + plotW, y1: Y(v), y2: Y(v)}, svg);
    el("svg:text", {x: LEFT - 5, y: Y(v) + 4, "text-anchor": "end"}, svg, fmt(v));
  }
  el("svg:rect", {class: "frame", x: LEFT, y: TOP, width: plotW, height: plotH}, svg);
  el("svg:text", {class: "title", x: LEFT, y: 17}, svg, title);
  el("svg:text", {x: LEFT + plotW / 2, y: H - 6, "text-anchor": "middle"}, svg, xName);
  el("svg:text", {x: 14, y: TOP + plotH / 2, "text-anchor": "middle",
                  transform: `rotate(-90 14 ${TOP + plotH / 2})`}, svg, yName);
  return {X, Y};
}

// Direction sessions, left: each source's azimuth (a line's cone angle) against time,
// coloured by id; hollow where not heard (a prediction).
function drawDirectionsInTime(svg, directions, linear) {
  const angle = d => (linear ? d.cone_angle_rad : d.azimuth_rad);
  const pts = directions.filter(d => angle(d) !== null);
  const t1 = pts.length ? pts[pts.length - 1].t_s : 1, t0 = pts.length ? Math.min(pts[0].t_s, t1 - 1) : 0;
  const {X, Y} = axes(svg, linear ? "cone angle against time" : "azimuth against time", "t (s)",
                      linear ? "cone angle (deg)" : "azimuth (deg)", t0, t1, linear ? 0 : -180, 180,
                      tickStep(t1 - t0), linear ? 30 : 45);
  for (const d of pts) {
    const c = el("svg:circle", {class: "direction", cx: X(d.t_s), cy: Y(angle(d) * DEG), r: 2,
                                fill: d.source_present ? colourOf(d.id) : "none", stroke: colourOf(d.id)}, svg);
    el("svg:title", {}, c, `source ${d.id} at ${fmt(d.t_s)} s: ${fmt(angle(d) * DEG)} deg`);
  }
}

// Direction sessions, right: the latest frame's sources on an azimuth-elevation map (a line:
// its cone angles on one axis), labelled with their ids.
function drawDirectionMap(svg, sources, linear) {
  const {X, Y} = linear ? axes(svg, "cone angles now", "cone angle (deg)", "", 0, 180, -1, 1, 30, 1)
                        : axes(svg, "directions now", "azimuth (deg)", "elevation (deg)", -180, 180, -90, 90, 45, 30);
  for (const s of sources) {
    const a = linear ? s.cone_angle_rad : s.azimuth_rad, e = linear ? 0 : s.elevation_rad;
    if (a === null || e === null) continue;
    const g = el("svg:g", {class: "source"}, svg);
    el("svg:circle", {cx: X(a * DEG), cy: Y(linear ? 0 : e * DEG), r: 6, fill: s.source_present ? colourOf(s.id) : "#fff",
                      stroke: colourOf(s.id), "stroke-width": 2}, g);
    el("svg:text", {x: X(a * DEG) + 8, y: Y(linear ? 0 : e * DEG) - 8}, g, String(s.id));
    el("svg:title", {}, g, `source ${s.id}: ` + (linear ? `cone ${fmt(a * DEG)} deg` :
                                                 `azimuth ${fmt(a * DEG)}, elevation ${fmt(e * DEG)} deg`));
  }
}

const cards = new Map();  // card key ("live:ID" or "ended:ID") -> {root, heading, meta, xy, xz, ...}

function card(key, parentId) {
  let c = cards.get(key);
  if (c) return c;
  const root = el("section", {class: "session", "data-id": key.slice(key.indexOf(":") + 1)},
                  document.getElementById(parentId));
  c = {root, heading: el("h2", {}, root), meta: el("div", {class: "meta"}, root)};
  c.badges = el("div", {class: "badges"}, c.meta);
  c.text = el("span", {}, c.meta);
  const panels = el("div", {class: "panels"}, root);
  c.xy = el("svg:svg", {class: "plot xy", viewBox: `0 0 ${W} ${H}`}, panels);
  c.xz = el("svg:svg", {class: "plot xz", viewBox: `0 0 ${W} ${H}`}, panels);
  cards.set(key, c);
  return c;
}

// A replay shows an ended session's track growing from its first fix to its last, in at most
// REPLAY_S seconds (real time when the session was shorter).
const REPLAY_S = 10;
function replayCut(c, s) {
  if (!c.replay) return Infinity;
  const times = s.track.map(p => p.t_s).concat(s.directions.map(d => d.t_s)).filter(t => t !== null);
  if (!times.length) { c.replay = null; return Infinity; }
  const t0 = Math.min(...times), t1 = Math.max(...times);
  const speed = Math.max(1, (t1 - t0) / REPLAY_S);
  const cut = t0 + (performance.now() - c.replay.start) / 1000 * speed;
  if (cut >= t1) { c.replay = null; return Infinity; }
  return cut;
}

// One session's card: its text, badges and plots; `cut_t`: draw only what came before it
// (a replay).
function drawSession(c, whole, cut_t) {
  const s = cut_t === Infinity ? whole : Object.assign({}, whole, {
    track: whole.track.filter(p => p.t_s <= cut_t),
    directions: whole.directions.filter(d => d.t_s <= cut_t)});
  const last = s.track.length ? s.track[s.track.length - 1] : null;
  let meta = `${s.backend} / ${s.filter_type} / ${s.attached ? "attached" : "detached"} / ` +
             `${s.frames} frames, ${s.track.length} track points`;
  if (last) meta += ` / t ${fmt(last.t_s)} s at (${last.position_m.map(v => v === null ? "?" : v.toFixed(2)).join(", ")}) m`;
  if (s.kind === "detections") {
    const confirmed = s.targets.filter(t => t.status !== "tentative").length;
    meta = `track-while-scan / ${s.attached ? "attached" : "detached"} / ${s.frames} scans, ` +
           `${confirmed} confirmed of ${s.targets.length} tracks`;
  }
  if (s.platform) {
    meta += " / platform roll, pitch, yaw (" + s.platform.euler_rad.map(v => v === null ? "?" : (v * 180 / Math.PI).toFixed(1)).join(", ") + ") deg";
  }
  if (s.model_probabilities.length) {
    meta += " / models " + s.model_probabilities.map(m => `${m.model} ${(100 * m.probability).toFixed(0)}%`).join(" ");
  }
  c.text.textContent = meta;
  // The latest frame's presence (present / silent) and ambiguity, as badges.
  while (c.badges.firstChild) c.badges.removeChild(c.badges.firstChild);
  const pr = s.presence;
  if (pr) {
    const tip = pr.state === "untested" ? "the engine ran no presence test" :
        `presence statistic ${fmt(pr.statistic || 0)}, threshold ${fmt(pr.threshold || 0)}; ` +
        `${s.present_frames} of ${s.frames} frames held a source`;
    el("span", {class: "presence " + pr.state, title: tip}, c.badges,
       pr.state === "untested" ? "presence n/a" : pr.state);
    if (pr.ambiguous) {
      el("span", {class: "presence ambiguous", title: "several position hypotheses fit the data"},
         c.badges, `ambiguous: ${pr.modes} modes`);
    }
    if (pr.far_field) {
      el("span", {class: "presence far", title: `this frame bounds the direction, not the range ` +
                                                 `(range sd ${fmt(pr.range_sd_m || 0)} m)`},
         c.badges, "far field: direction only");
    }
  }
  const silent = !!(pr && pr.state === "silent");
  // Directions, and positions from planar and linear arrays, come as a list of sources.
  if (s.localization === "direction" || (s.array_shape && s.array_shape !== "volumetric")) {
    const linear = s.array_shape === "linear";
    c.text.textContent += ` / ${s.array_shape} array, directions: ${s.sources.length} source(s) now`;
    drawDirectionsInTime(c.xy, s.directions, linear);
    drawDirectionMap(c.xz, s.sources, linear);
  } else {
    drawPanel(c.xy, "x-y (top view)", 0, 1, s.sensors_m, s.track, s.targets, silent);
    drawPanel(c.xz, "x-z (side view)", 0, 2, s.sensors_m, s.track, s.targets, silent);
  }
}

function render(doc) {
  const seen = new Set();
  for (const s of doc.sessions) {
    const key = "live:" + s.id;
    seen.add(key);
    const c = card(key, "sessions");
    c.heading.textContent = (s.label || "(no label)") + "  [" + s.id + "]";
    drawSession(c, s, Infinity);
  }
  // Ended sessions, most recent first: drawn whole, or as far as their replay has come.
  const ended = doc.finished || [];
  document.getElementById("finished-title").hidden = !ended.length;
  for (const f of ended) {
    const s = f.session, key = "ended:" + s.id;
    seen.add(key);
    const fresh = !cards.has(key);
    const c = card(key, "finished");
    if (fresh) {
      c.root.classList.add("finished");
      c.title = el("span", {}, c.heading);
      c.button = el("button", {class: "replay", type: "button"}, c.heading, "replay");
      c.button.addEventListener("click", () => { c.replay = {start: performance.now()}; drawEnded(c); });
      if (s.id === replayId) c.replay = {start: performance.now()};  // /?replay=ID: a link to a replay
    }
    c.session = s;
    c.title.textContent = (s.label || "(no label)") + "  [" + s.id + "]  ended " +
                          fmt(f.finished_ago_s) + " s ago (" + f.reason + ")";
    drawEnded(c);
  }
  for (const [key, c] of cards) if (!seen.has(key)) { c.root.remove(); cards.delete(key); }
  const shown = doc.sessions.length ? `${doc.sessions_total} session(s)` :
      "no sessions (stream one, e.g. localizer-cli simulate --server HOST:PORT)";
  document.getElementById("status").textContent =
      `localizer ${doc.version}: ${shown}` + (ended.length ? `, ${ended.length} ended` : "") +
      `; updated ${new Date().toLocaleTimeString()}`;
}

function drawEnded(c) {
  const cut = replayCut(c, c.session);
  c.button.textContent = cut === Infinity ? "replay" : "replaying ...";
  drawSession(c, c.session, cut);
}

// Replays advance ten times a second, between polls.
setInterval(() => { for (const c of cards.values()) if (c.replay && c.session) drawEnded(c); }, 100);

// A server started with --auth-token-file serves this page at /?token=OPERATOR_TOKEN; the
// token goes on to /sessions as an Authorization header (never into another URL).
const pageToken = new URLSearchParams(location.search).get("token");
const replayId = new URLSearchParams(location.search).get("replay");
const authHeaders = pageToken ? {Authorization: "Bearer " + pageToken} : {};

async function poll() {
  try {
    const response = await fetch("/sessions", {cache: "no-store", headers: authHeaders});
    if (!response.ok) throw new Error(`/sessions answered ${response.status}`);
    render(await response.json());
  } catch (e) {
    document.getElementById("status").textContent = "cannot read /sessions: " + e.message;
  } finally {
    setTimeout(poll, 500);
  }
}
poll();
</script>
</body>
</html>
)html";

}  // namespace

std::string_view LivePageHtml() { return kPage; }

}  // namespace localizer::server
