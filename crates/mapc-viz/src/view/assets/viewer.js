// mapc view: plays a replay written by `mapc view`. No build step, no library: the data is the JSON in
// #mapc-data (or data.json from `mapc view --serve`), the drawing is plain canvas.
"use strict";

const $ = (id) => document.getElementById(id);

// An element with properties (`style`: an object of style properties) and children; strings become text nodes.
// The page builds every element this way and never parses HTML: text from a map (any text its author chose) is
// shown as text, and the page's Content-Security-Policy makes the browser refuse HTML parsed from a string.
function element(tag, props, ...children) {
  const node = document.createElement(tag);
  for (const [k, v] of Object.entries(props || {})) {
    if (k === "style") Object.assign(node.style, v); else node[k] = v;
  }
  node.append(...children);
  return node;
}

const status = $("mapc-status");
const stats = { framesDrawn: 0, vehiclesDrawn: 0, readyMs: null };

function decode(b64, Type) {
  const bin = atob(b64);
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  return new Type(bytes.buffer);
}

// ---- geometry: roads and connections as polylines with cumulative lengths ----

function polyline(pts) {
  const xs = [], ys = [], cum = [0];
  for (let i = 0; i < pts.length; i += 2) { xs.push(pts[i]); ys.push(pts[i + 1]); }
  for (let i = 1; i < xs.length; i++) cum.push(cum[i - 1] + Math.hypot(xs[i] - xs[i - 1], ys[i] - ys[i - 1]));
  return { xs, ys, cum, len: cum[cum.length - 1] };
}

// The point and heading at fraction `f` of a polyline's drawn length.
function along(pl, f) {
  const s = Math.min(Math.max(f, 0), 1) * pl.len;
  let lo = 0, hi = pl.cum.length - 1;
  while (hi - lo > 1) { const mid = (lo + hi) >> 1; if (pl.cum[mid] <= s) lo = mid; else hi = mid; }
  const seg = pl.cum[hi] - pl.cum[lo] || 1;
  const u = (s - pl.cum[lo]) / seg;
  const dx = pl.xs[hi] - pl.xs[lo], dy = pl.ys[hi] - pl.ys[lo];
  return [pl.xs[lo] + u * dx, pl.ys[lo] + u * dy, Math.atan2(dy, dx)];
}

// ---- lanes: right-hand traffic, lane 0 rightmost, every lane of a road drawn beside the others ----

const LANE_WIDTH_M = 3.2;
// Lanes stay this many pixels apart however far out the view is zoomed, so a lane change shows at any scale.
const MIN_LANE_SPACING_PX = 4;

function laneSpacingPx() { return Math.max(LANE_WIDTH_M * view.scale, MIN_LANE_SPACING_PX); }

// Offset to the left of the centre line, in pixels, of lane `k` of a road with `lanes` lanes.
function laneOffsetPx(lanes, k) { return lanes > 1 ? (k - (lanes - 1) / 2) * laneSpacingPx() : 0; }

// Screen points of a polyline moved `d` pixels to the left of its direction (mitred at the vertices).
function offsetScreenPath(pts, d) {
  if (d === 0 || pts.length < 2) return pts;
  const n = pts.length, out = [];
  const normal = (a, b) => {
    const dx = b[0] - a[0], dy = b[1] - a[1], l = Math.hypot(dx, dy) || 1;
    return [dy / l, -dx / l]; // the left of travel on a screen whose y grows downwards
  };
  for (let i = 0; i < n; i++) {
    const na = normal(pts[Math.max(i - 1, 0)], pts[Math.max(i, 1)]);
    const nb = normal(pts[Math.min(i, n - 2)], pts[Math.min(i + 1, n - 1)]);
    let mx = na[0] + nb[0], my = na[1] + nb[1];
    const ml = Math.hypot(mx, my) || 1;
    mx /= ml; my /= ml;
    const k = Math.min(1 / Math.max(mx * na[0] + my * na[1], 0.25), 4);
    out.push([pts[i][0] + mx * d * k, pts[i][1] + my * d * k]);
  }
  return out;
}

function segmentDistance(px, py, ax, ay, bx, by) {
  const dx = bx - ax, dy = by - ay, l2 = dx * dx + dy * dy;
  const u = l2 > 0 ? Math.min(Math.max(((px - ax) * dx + (py - ay) * dy) / l2, 0), 1) : 0;
  return Math.hypot(px - ax - u * dx, py - ay - u * dy);
}

// ---- colours ----

function speedScale(stops) {
  const lut = [];
  for (let i = 0; i < 256; i++) {
    const t = i / 255;
    let k = 0;
    while (k < stops.length - 2 && t > stops[k + 1][0]) k++;
    const [t0, c0] = [stops[k][0], stops[k].slice(1)], [t1, c1] = [stops[k + 1][0], stops[k + 1].slice(1)];
    const u = Math.min(Math.max((t - t0) / (t1 - t0), 0), 1);
    lut.push(c0.map((c, j) => Math.round(c + u * (c1[j] - c))));
  }
  return lut;
}

// Humans blue, AVs orange; darker is faster.
function vehicleColor(av, t) {
  const light = 78 - 50 * Math.min(Math.max(t, 0), 1);
  return av ? `hsl(22, 92%, ${light}%)` : `hsl(212, 70%, ${light}%)`;
}

// ---- the data ----

function prepareNetwork(net) {
  const byId = new Map();
  for (const r of net.roads) { r.pl = polyline(r.pts); byId.set(r.id, r); }
  let minX = Infinity, minY = Infinity, maxX = -Infinity, maxY = -Infinity;
  for (const r of net.roads) for (let i = 0; i < r.pts.length; i += 2) {
    minX = Math.min(minX, r.pts[i]); maxX = Math.max(maxX, r.pts[i]);
    minY = Math.min(minY, r.pts[i + 1]); maxY = Math.max(maxY, r.pts[i + 1]);
  }
  for (const j of net.junctions) {
    minX = Math.min(minX, j.x); maxX = Math.max(maxX, j.x); minY = Math.min(minY, j.y); maxY = Math.max(maxY, j.y);
  }
  net.bounds = [minX, minY, maxX, maxY];
  net.byId = byId;
  net.drawOrder = net.roads.slice().sort((a, b) => b.rank - a.rank);
  return net;
}

function prepareReplay(rep, net) {
  for (const lane of rep.lanes) {
    if (lane.road !== undefined) {
      lane.pl = net.roads[lane.road].pl;
    } else {
      const a = net.roads[lane.from].pl, b = net.roads[lane.to].pl;
      const ax = a.xs[a.xs.length - 1], ay = a.ys[a.ys.length - 1];
      lane.pl = polyline([ax, ay, b.xs[0], b.ys[0]]);
    }
    lane.factor = lane.pl.len > 0 && lane.length > 0 ? 1 / lane.length : 0;
    lane.roadLanes = net.roads[lane.road !== undefined ? lane.road : lane.from].lanes; // a connection: its from road's
  }
  const v = rep.vehicles;
  v.type = decode(v.type, Uint16Array);
  v.first = decode(v.first, Uint32Array);
  v.count = decode(v.count, Uint32Array);
  v.offset = decode(v.offset, Uint32Array);
  rep.rows.lane = decode(rep.rows.lane, Uint16Array);
  rep.rows.lane_index = decode(rep.rows.lane_index, Uint8Array);
  rep.rows.pos = decode(rep.rows.pos, Float32Array);
  rep.rows.speed = decode(rep.rows.speed, Uint16Array);
  for (const k of ["outflow", "inflow", "speed"]) rep.metrics[k] = decode(rep.metrics[k], Float32Array);
  rep.metrics.on_road = decode(rep.metrics.on_road, Uint32Array);
  return rep;
}

// ---- panes ----

const view = { scale: 1, cx: 0, cy: 0 }; // shared by every pane: pixels per metre and the world centre

function fitView(net, canvas) {
  const [x0, y0, x1, y1] = net.bounds;
  const w = canvas.clientWidth, h = canvas.clientHeight;
  view.scale = 0.92 * Math.min(w / Math.max(x1 - x0, 1), h / Math.max(y1 - y0, 1));
  view.cx = (x0 + x1) / 2; view.cy = (y0 + y1) / 2;
}

function toScreen(canvas, x, y) {
  return [canvas.clientWidth / 2 + (x - view.cx) * view.scale, canvas.clientHeight / 2 - (y - view.cy) * view.scale];
}

function toWorld(canvas, sx, sy) {
  return [view.cx + (sx - canvas.clientWidth / 2) / view.scale, view.cy - (sy - canvas.clientHeight / 2) / view.scale];
}

function sizeCanvas(canvas) {
  const dpr = window.devicePixelRatio || 1;
  const w = Math.max(1, Math.round(canvas.clientWidth * dpr)), h = Math.max(1, Math.round(canvas.clientHeight * dpr));
  if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
  const ctx = canvas.getContext("2d");
  ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  return ctx;
}

function drawNetwork(ctx, canvas, net) {
  ctx.lineJoin = "round"; ctx.lineCap = "round";
  const screenPts = (r) => r.pl.xs.map((x, i) => toScreen(canvas, x, r.pl.ys[i]));
  const path = (r, d = 0) => {
    ctx.beginPath();
    offsetScreenPath(screenPts(r), d).forEach(([sx, sy], i) => { if (i === 0) ctx.moveTo(sx, sy); else ctx.lineTo(sx, sy); });
  };
  for (const r of net.drawOrder) if (r.window !== undefined) {
    path(r); ctx.strokeStyle = "rgba(255, 196, 0, 0.45)"; ctx.lineWidth = Math.max(14, 14 * view.scale); ctx.stroke();
  }
  for (const r of net.drawOrder) {
    ctx.strokeStyle = r.color;
    if (r.lanes > 1) { // one line per lane, with a gap between neighbours
      ctx.lineWidth = Math.max(1.2, 0.6 * laneSpacingPx());
      for (let k = 0; k < r.lanes; k++) { path(r, laneOffsetPx(r.lanes, k)); ctx.stroke(); }
    } else {
      path(r); ctx.lineWidth = Math.max(1.5, Math.min(3.5 * view.scale, 40)); ctx.stroke();
    }
  }
  ctx.font = "11px system-ui, sans-serif"; ctx.textBaseline = "bottom";
  const windowJunctions = new Set(net.windows.map((w) => w.junction));
  for (const j of net.junctions) {
    const shown = j.kind === "merge" || j.kind === "diverge" || windowJunctions.has(j.id);
    if (!shown) continue;
    const [sx, sy] = toScreen(canvas, j.x, j.y);
    ctx.beginPath(); ctx.arc(sx, sy, 4, 0, 2 * Math.PI);
    ctx.fillStyle = j.kind === "merge" ? "#111" : "#fff"; ctx.fill();
    ctx.strokeStyle = "#111"; ctx.lineWidth = 1.2; ctx.stroke();
    ctx.fillStyle = "#111"; ctx.fillText(j.id, sx + 6, sy - 3);
  }
}

function drawVehicles(ctx, canvas, pane, frame) {
  const rep = pane.replay, v = rep.vehicles, rows = rep.rows;
  const vmax = DATA.speed_scale.max_mps;
  const big = 5 * view.scale >= 6;
  pane.drawn = [];
  for (let i = 0; i < v.first.length; i++) {
    if (v.first[i] > frame) break; // tracks are in entry order
    if (frame >= v.first[i] + v.count[i]) continue;
    const k = v.offset[i] + frame - v.first[i];
    const lane = rep.lanes[rows.lane[k]];
    const [x, y, heading] = along(lane.pl, rows.pos[k] * lane.factor);
    const d = laneOffsetPx(lane.roadLanes, rows.lane_index[k]);
    const [cx, cy] = toScreen(canvas, x, y);
    const sx = cx - Math.sin(heading) * d, sy = cy - Math.cos(heading) * d; // `d` to the left of travel
    if (sx < -20 || sy < -20 || sx > canvas.clientWidth + 20 || sy > canvas.clientHeight + 20) continue;
    const speed = rows.speed[k] / 100;
    const av = rep.types[v.type[i]].av;
    const len = rep.types[v.type[i]].length_m || 5; // trucks and buses drawn longer
    ctx.fillStyle = vehicleColor(av, speed / vmax);
    ctx.beginPath();
    if (big) {
      ctx.save(); ctx.translate(sx, sy); ctx.rotate(-heading);
      ctx.rect(-len * view.scale, -1 * view.scale, len * view.scale, 2 * view.scale); // the front is at the position
      ctx.restore();
    } else {
      ctx.arc(sx, sy, av ? 3.2 : 2.6, 0, 2 * Math.PI);
    }
    ctx.fill();
    if (av) { ctx.strokeStyle = "#000"; ctx.lineWidth = 0.8; ctx.stroke(); }
    pane.drawn.push([sx, sy, i, k]);
  }
  return pane.drawn.length;
}

// Fixed-time lights: the letter of link `index` at `t` seconds into the run (the simulator's rule).
function lightLetter(light, index, t) {
  const cycle = light.phases.reduce((a, p) => a + p[0], 0);
  if (!(cycle > 0)) return "G";
  let into = (((t - light.offset_s) % cycle) + cycle) % cycle;
  for (const [d, state] of light.phases) {
    if (into < d) return state[index] || "G";
    into -= d;
  }
  return "G";
}

// A bar across each controlled lane at its stop line, in the colour of the light's phase at `t`.
function drawLights(ctx, canvas, net, t) {
  if (!net.lights) return;
  for (const light of net.lights) for (const [roadId, lane, index] of light.links) {
    const r = net.byId.get(roadId);
    if (!r || r.pl.xs.length < 2) continue;
    const n = r.pl.xs.length;
    const [ex, ey] = toScreen(canvas, r.pl.xs[n - 1], r.pl.ys[n - 1]);
    const [px, py] = toScreen(canvas, r.pl.xs[n - 2], r.pl.ys[n - 2]);
    const l = Math.hypot(ex - px, ey - py) || 1;
    const nx = (ey - py) / l, ny = -(ex - px) / l; // the left of travel on screen
    const d = laneOffsetPx(r.lanes, lane), half = Math.max(6, 0.6 * laneSpacingPx());
    const cx = ex + nx * d, cy = ey + ny * d;
    const c = lightLetter(light, index, t);
    ctx.lineCap = "butt";
    ctx.beginPath(); ctx.moveTo(cx - nx * half, cy - ny * half); ctx.lineTo(cx + nx * half, cy + ny * half);
    ctx.strokeStyle = "#111"; ctx.lineWidth = 7; ctx.stroke(); // an outline, to stand out on any road colour
    ctx.strokeStyle = "GgoO".includes(c) ? "#2ecc40" : "yY".includes(c) ? "#ffdc00" : "#ff2d2d";
    ctx.lineWidth = 4; ctx.stroke();
  }
}

// The time-space diagram: drawn once into an image, then the cursor on top.
function timeSpaceImage(pane, w, h) {
  const rep = pane.replay, v = rep.vehicles, rows = rep.rows;
  let y0 = Infinity, y1 = -Infinity;
  for (const lane of rep.lanes) if (lane.corridor_start !== undefined) {
    y0 = Math.min(y0, lane.corridor_start); y1 = Math.max(y1, lane.corridor_start + lane.length);
  }
  const box = { left: 52, right: 8, top: 8, bottom: 26, y0, y1 };
  if (!(y1 > y0)) return { box, image: null };
  const pw = w - box.left - box.right, ph = h - box.top - box.bottom;
  const image = new ImageData(Math.max(1, pw), Math.max(1, ph));
  const px = image.data, lut = DATA.lut, vmax = DATA.speed_scale.max_mps, frames = rep.frames;
  const plot = (c, r, rgb) => {
    if (c < 0 || r < 0 || c >= pw || r >= ph) return;
    const o = 4 * (r * pw + c);
    px[o] = rgb[0]; px[o + 1] = rgb[1]; px[o + 2] = rgb[2]; px[o + 3] = 255;
  };
  // each vehicle's trajectory as line pieces between its samples, coloured by the speed at the piece's start
  for (let i = 0; i < v.first.length; i++) {
    const av = rep.types[v.type[i]].av;
    let pc = null, pr = null;
    for (let j = 0; j < v.count[i]; j++) {
      const k = v.offset[i] + j, lane = rep.lanes[rows.lane[k]];
      if (lane.corridor_start === undefined) { pc = null; continue; }
      const c = ((v.first[i] + j) / Math.max(frames - 1, 1)) * (pw - 1);
      const r = (1 - (lane.corridor_start + rows.pos[k] - y0) / (y1 - y0)) * (ph - 1);
      const rgb = av ? [0, 0, 0] : lut[Math.min(255, Math.max(0, Math.round((rows.speed[k] / 100 / vmax) * 255)))];
      if (pc === null) plot(Math.round(c), Math.round(r), rgb);
      else {
        const n = Math.max(1, Math.ceil(Math.max(Math.abs(c - pc), Math.abs(r - pr))));
        for (let s = 1; s <= n; s++) plot(Math.round(pc + ((c - pc) * s) / n), Math.round(pr + ((r - pr) * s) / n), rgb);
      }
      pc = c; pr = r;
    }
  }
  return { box, image };
}

function drawTimeSpace(pane, frame) {
  const canvas = pane.ts, ctx = sizeCanvas(canvas), w = canvas.clientWidth, h = canvas.clientHeight;
  const key = `${w}x${h}`;
  if (pane.tsKey !== key) {
    pane.tsKey = key;
    pane.tsImage = timeSpaceImage(pane, w, h);
    if (pane.tsImage.image) {
      const off = document.createElement("canvas");
      off.width = pane.tsImage.image.width; off.height = pane.tsImage.image.height;
      off.getContext("2d").putImageData(pane.tsImage.image, 0, 0);
      pane.tsImage.canvas = off;
    }
  }
  const { box, canvas: img } = pane.tsImage, rep = pane.replay;
  ctx.clearRect(0, 0, w, h);
  ctx.fillStyle = "#fff"; ctx.fillRect(0, 0, w, h);
  ctx.font = "11px system-ui, sans-serif"; ctx.fillStyle = "#444";
  if (!img) { ctx.fillText("no vehicle on the corridor's main line", 10, 20); return; }
  ctx.drawImage(img, box.left, box.top);
  const pw = w - box.left - box.right, ph = h - box.top - box.bottom;
  ctx.strokeStyle = "#999"; ctx.strokeRect(box.left - 0.5, box.top - 0.5, pw + 1, ph + 1);
  const t0 = rep.start_s, t1 = rep.start_s + (rep.frames - 1) * rep.step_s;
  ctx.textBaseline = "top"; ctx.textAlign = "center";
  for (const t of ticks(t0, t1, 6)) ctx.fillText(`${t} s`, box.left + ((t - t0) / (t1 - t0 || 1)) * pw, box.top + ph + 4);
  ctx.textAlign = "right"; ctx.textBaseline = "middle";
  for (const y of ticks(box.y0, box.y1, 6)) ctx.fillText(`${y} m`, box.left - 4, box.top + (1 - (y - box.y0) / (box.y1 - box.y0)) * ph);
  const cx = box.left + (frame / Math.max(rep.frames - 1, 1)) * pw;
  ctx.strokeStyle = "#0057d9"; ctx.lineWidth = 1.5; ctx.beginPath(); ctx.moveTo(cx, box.top); ctx.lineTo(cx, box.top + ph); ctx.stroke();
  ctx.textAlign = "left";
}

function ticks(a, b, n) {
  const span = b - a;
  if (!(span > 0)) return [a];
  const raw = span / n, mag = Math.pow(10, Math.floor(Math.log10(raw)));
  const step = [1, 2, 5, 10].map((m) => m * mag).find((s) => s >= raw);
  const out = [];
  for (let t = Math.ceil(a / step) * step; t <= b + 1e-9; t += step) out.push(Math.round(t * 100) / 100);
  return out;
}

function drawPane(pane, frame) {
  const ctx = sizeCanvas(pane.map);
  ctx.clearRect(0, 0, pane.map.clientWidth, pane.map.clientHeight);
  drawNetwork(ctx, pane.map, DATA.network);
  let n = 0;
  if (pane.replay) {
    const f = Math.min(frame, pane.replay.frames - 1);
    n = drawVehicles(ctx, pane.map, pane, f);
    const rep = pane.replay;
    drawLights(ctx, pane.map, DATA.network, rep.start_s + f * rep.step_s - (DATA.network.light_clock_start_s || 0));
    drawTimeSpace(pane, f);
    const m = pane.replay.metrics, warm = f <= pane.replay.warmup_frames;
    if (warm && pane.replay.warmup_frames > 0) {
      const at = fmt(pane.replay.start_s + pane.replay.warmup_frames * pane.replay.step_s, 1);
      pane.metrics.replaceChildren(element("span", { className: "note" }, `warm-up: metrics start at ${at} s`));
    } else {
      pane.metrics.replaceChildren(
        "outflow ", element("b", null, fmt(m.outflow[f], 1)), " veh/h \u00a0 inflow ", element("b", null, fmt(m.inflow[f], 1)),
        " veh/h \u00a0 mean speed ", element("b", null, fmt(m.speed[f], 2)), " m/s \u00a0 on the road ",
        element("b", null, String(m.on_road[f])));
    }
    pane.outflow = m.outflow[f];
  }
  return n;
}

const fmt = (x, d) => Number(x).toFixed(d);

// ---- the player ----

const player = { frame: 0, playing: false, rate: 10, last: null, simTime: 0 };

function frameCount() { return Math.max(1, ...DATA.replays.map((r) => r.frames)); }
function stepS() { return DATA.replays.length ? DATA.replays[0].step_s : 1; }

function render() {
  let vehicles = 0;
  for (const pane of panes) vehicles += drawPane(pane, player.frame);
  stats.framesDrawn += 1; stats.vehiclesDrawn = vehicles;
  if (stats.readyMs === null) stats.readyMs = Math.round(performance.now());
  if (DATA.replays.length) {
    const r = DATA.replays[0];
    $("slider").value = player.frame;
    const kept = r.kept ? ` (${r.kept})` : "";
    $("clock").textContent = `t = ${fmt(r.start_s + player.frame * r.step_s, 1)} s / ${fmt(r.start_s + (r.frames - 1) * r.step_s, 0)} s${kept}`;
  }
  status.dataset.framesDrawn = stats.framesDrawn;
  status.dataset.vehiclesDrawn = stats.vehiclesDrawn;
  status.dataset.frame = player.frame;
  status.dataset.readyMs = stats.readyMs;
  if (panes.length && panes[0].outflow !== undefined) status.dataset.outflow = fmt(panes[0].outflow, 3);
  status.textContent = `frame ${player.frame}, ${vehicles} vehicles drawn, ${stats.framesDrawn} frames drawn`;
}

// Timers rather than requestAnimationFrame: they follow a headless browser's virtual clock, so a test can play
// the page to its end in a moment; 60 ticks a second look the same.
const TICK_MS = 1000 / 60;

function tick() {
  if (!player.playing) { player.last = null; return; }
  const now = performance.now();
  if (player.last !== null) {
    player.simTime += ((now - player.last) / 1000) * player.rate;
    const f = Math.floor(player.simTime / stepS());
    if (f >= frameCount() - 1) { player.frame = frameCount() - 1; setPlaying(false); }
    else player.frame = f;
  }
  player.last = now;
  render();
  setTimeout(tick, TICK_MS);
}

function setPlaying(on) {
  player.playing = on;
  $("play").textContent = on ? "\u275a\u275a" : "\u25b6";
  if (on) {
    if (player.frame >= frameCount() - 1) player.frame = 0;
    player.simTime = player.frame * stepS(); player.last = null;
    setTimeout(tick, 0);
  }
}

function seek(frame) {
  player.frame = Math.min(Math.max(0, frame), frameCount() - 1);
  player.simTime = player.frame * stepS();
  render();
}

// ---- hovering ----

// What lies under the screen point: a vehicle, else a junction, else a road (`only` restricts the kind).
function describe(pane, sx, sy, only) {
  const net = DATA.network;
  if (pane.drawn && (!only || only === "vehicle")) {
    let best = null, bd = 8;
    for (const d of pane.drawn) { const dd = Math.hypot(d[0] - sx, d[1] - sy); if (dd < bd) { bd = dd; best = d; } }
    if (best) {
      const rep = pane.replay, v = rep.vehicles, k = best[3], type = rep.types[v.type[best[2]]];
      return `vehicle ${v.ids[best[2]]} · ${type.name}${type.av ? " (AV)" : ""}\n` +
        `${fmt(rep.rows.speed[k] / 100, 2)} m/s · ${rep.lanes[rep.rows.lane[k]].name}` +
        `${rep.lanes[rep.rows.lane[k]].roadLanes > 1 ? ` lane ${rep.rows.lane_index[k]}` : ""} at ${fmt(rep.rows.pos[k], 1)} m`;
    }
  }
  for (const j of only && only !== "junction" ? [] : net.junctions) {
    const [jx, jy] = toScreen(pane.map, j.x, j.y);
    if (Math.hypot(jx - sx, jy - sy) < 7) {
      return `junction ${j.id} · ${j.kind}\n${j.provenance || "no provenance"}\nin: ${j.roads_in.join(", ") || "none"} · out: ${j.roads_out.join(", ") || "none"}`;
    }
  }
  const [wx, wy] = toWorld(pane.map, sx, sy), tol = 6 / view.scale;
  for (const r of net.drawOrder.slice().reverse()) {
    for (let i = 1; i < r.pl.xs.length; i++) {
      if (segmentDistance(wx, wy, r.pl.xs[i - 1], r.pl.ys[i - 1], r.pl.xs[i], r.pl.ys[i]) < tol) {
        const win = r.window !== undefined ? `\nin ${net.windows[r.window].label}` : "";
        return `road ${r.id} · ${r.label} (${r.class})\n${r.lanes} lane${r.lanes > 1 ? "s" : ""} · ${fmt(r.length_m, 1)} m · ` +
          `${fmt(r.speed_mps, 1)} m/s · priority ${r.priority}\n${r.provenance || "no provenance"}${win}`;
      }
    }
  }
  return null;
}

function attachInteraction(pane) {
  const c = pane.map, tip = $("tip");
  let drag = null;
  c.addEventListener("mousedown", (e) => { drag = [e.clientX, e.clientY]; c.classList.add("dragging"); });
  window.addEventListener("mouseup", () => { drag = null; c.classList.remove("dragging"); });
  c.addEventListener("mousemove", (e) => {
    const rect = c.getBoundingClientRect(), sx = e.clientX - rect.left, sy = e.clientY - rect.top;
    if (drag) {
      view.cx -= (e.clientX - drag[0]) / view.scale; view.cy += (e.clientY - drag[1]) / view.scale;
      drag = [e.clientX, e.clientY]; tip.hidden = true; render(); return;
    }
    showTip(pane, sx, sy, describe(pane, sx, sy));
  });
  c.addEventListener("mouseleave", () => { tip.hidden = true; });
  c.addEventListener("wheel", (e) => {
    e.preventDefault();
    const rect = c.getBoundingClientRect(), sx = e.clientX - rect.left, sy = e.clientY - rect.top;
    const [wx, wy] = toWorld(c, sx, sy);
    view.scale *= Math.exp(-e.deltaY * 0.0015);
    const [nx, ny] = toWorld(c, sx, sy);
    view.cx += wx - nx; view.cy += wy - ny;
    render();
  }, { passive: false });
  c.addEventListener("dblclick", () => { fitView(DATA.network, c); render(); });
  pane.ts.addEventListener("click", (e) => {
    const rect = pane.ts.getBoundingClientRect(), box = pane.tsImage && pane.tsImage.box;
    if (!box) return;
    const pw = pane.ts.clientWidth - box.left - box.right;
    seek(Math.round(((e.clientX - rect.left - box.left) / pw) * (pane.replay.frames - 1)));
  });
}

// ---- start ----

let DATA = null;
const panes = [];

function legend() {
  const net = DATA.network, seen = new Map();
  for (const r of net.roads) if (!seen.has(r.class)) seen.set(r.class, r);
  const swatch = (style) => element("i", { className: "swatch", style });
  const parts = [...seen.values()].sort((a, b) => a.rank - b.rank)
    .map((r) => element("span", null, swatch({ background: r.color }), r.class));
  if (net.windows.length) parts.push(element("span", null, swatch({ background: "rgba(255,196,0,0.6)" }), "controlled window"));
  if (DATA.replays.length) {
    const grad = DATA.lut.filter((_, i) => i % 32 === 0 || i === 255).map((c) => `rgb(${c.join(",")})`).join(",");
    parts.push(element("span", null, swatch({ background: vehicleColor(false, 0.7) }), "human"));
    parts.push(element("span", null, swatch({ background: vehicleColor(true, 0.7), outline: "1px solid #000" }), "AV (darker: faster)"));
    parts.push(element("span", null, "time-space speed 0",
      element("i", { className: "scale", style: { background: `linear-gradient(90deg,${grad})` } }),
      `${DATA.speed_scale.max_mps} m/s, AVs black`));
  }
  parts.push(element("span", null, "drag to pan, wheel to zoom, double-click to fit; hover for ids"));
  $("legend").replaceChildren(...parts);
}

function start(data) {
  DATA = data;
  DATA.lut = speedScale(DATA.speed_scale.stops);
  prepareNetwork(DATA.network);
  for (const r of DATA.replays) prepareReplay(r, DATA.network);
  $("title").textContent = DATA.title;
  $("subtitle").textContent = DATA.subtitle;
  const host = $("panes");
  const list = DATA.replays.length ? DATA.replays : [null];
  for (const rep of list) {
    const pane = {
      replay: rep, map: element("canvas", { className: "map" }), ts: rep ? element("canvas", { className: "ts" }) : null,
      metrics: element("div", { className: "metrics" }),
    };
    host.append(element("section", { className: "pane" + (rep ? "" : " single") },
      element("h2", null, rep ? rep.label : DATA.network.source), pane.metrics,
      element("div", { className: "row" }, pane.map, ...(pane.ts ? [pane.ts] : []))));
    if (!rep) pane.metrics.textContent = DATA.summary;
    panes.push(pane);
  }
  fitView(DATA.network, panes[0].map);
  for (const pane of panes) if (pane.replay) attachInteraction(pane); else attachMapOnly(pane);
  legend();
  if (DATA.replays.length) {
    $("controls").hidden = false;
    const rate = $("rate");
    for (const r of [1, 2, 5, 10, 20, 50]) rate.add(new Option(`${r}x`, r, r === player.rate, r === player.rate));
    rate.addEventListener("change", () => { player.rate = Number(rate.value); });
    $("slider").max = frameCount() - 1;
    $("slider").addEventListener("input", (e) => { setPlaying(false); seek(Number(e.target.value)); });
    $("play").addEventListener("click", () => setPlaying(!player.playing));
    document.addEventListener("keydown", (e) => { if (e.code === "Space") { e.preventDefault(); setPlaying(!player.playing); } });
  }
  window.addEventListener("resize", render);
  // #t=SECONDS starts there; #play starts playing; #rate=R sets the speed; #zoom=Z&at=X,Y zooms Z times the
  // whole-network view in around the world point X,Y (metres)
  const hash = new URLSearchParams(location.hash.slice(1));
  const zoom = Number(hash.get("zoom")), at = (hash.get("at") || "").split(",").map(Number);
  if (zoom > 0 && Number.isFinite(zoom)) view.scale *= zoom;
  if (at.length === 2 && at.every(Number.isFinite)) [view.cx, view.cy] = at;
  if (hash.has("rate")) player.rate = Number(hash.get("rate")) || player.rate;
  if (hash.has("t") && DATA.replays.length) seek(Math.round((Number(hash.get("t")) - DATA.replays[0].start_s) / stepS()));
  render();
  if (hash.has("hover")) pointAt(panes[0], hash.get("hover"));
  if (hash.has("play") && DATA.replays.length) setPlaying(true);
}

// #hover=ID shows the tooltip of a junction, road or vehicle (at the start frame) as if the mouse were on it.
function pointAt(pane, id) {
  const net = DATA.network;
  let at = null;
  const j = net.junctions.find((x) => x.id === id);
  if (j) at = [j.x, j.y];
  const r = net.byId.get(id);
  if (r) at = along(r.pl, 0.5);
  let text = null;
  if (at) {
    const [sx, sy] = toScreen(pane.map, at[0], at[1]);
    text = describe(pane, sx, sy, j ? "junction" : "road");
    showTip(pane, sx, sy, text);
  } else if (pane.drawn) {
    const d = pane.drawn.find((x) => pane.replay.vehicles.ids[x[2]] === id);
    if (d) { text = describe(pane, d[0], d[1], "vehicle"); showTip(pane, d[0], d[1], text); }
  }
  status.dataset.hover = text || `nothing called ${id} here`;
}

function showTip(pane, sx, sy, text) {
  const tip = $("tip"), rect = pane.map.getBoundingClientRect();
  tip.hidden = !text;
  if (text) { tip.textContent = text; tip.style.left = `${rect.left + sx + 14}px`; tip.style.top = `${rect.top + sy + 12}px`; }
}

function attachMapOnly(pane) {
  pane.ts = document.createElement("canvas"); // never shown: keeps one code path for interaction
  attachInteraction(pane);
}

const inline = $("mapc-data");
if (inline) start(JSON.parse(inline.textContent));
else fetch("data.json").then((r) => r.json()).then(start).catch((e) => { $("title").textContent = `could not load data.json: ${e}`; });
