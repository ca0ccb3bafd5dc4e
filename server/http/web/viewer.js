// The pathd viewer: lists the maps, draws one with its costs, follows its
// updates live (WatchMap as Server-Sent Events), plans between two clicked
// cells and draws the path (and, on request, the expanded cells), and shows
// the robots of Navigate sessions. Plain JavaScript against the HTTP API
// (docs/http.md); no library, no build step.
'use strict';

(() => {
  const $ = (id) => document.getElementById(id);
  const canvas = $('canvas');
  const ctx = canvas.getContext('2d');

  // Cell costs as RGBA: free white, costs 1..252 yellow to brown, inscribed
  // dark red, lethal near-black, unknown blue-grey (the map's cost model).
  const palette = new Uint32Array(256);
  const rgba = (r, g, b) => (255 << 24) | (b << 16) | (g << 8) | r;  // little-endian
  palette[0] = rgba(255, 255, 255);
  for (let c = 1; c <= 252; c++) {
    const t = (c - 1) / 251;
    palette[c] = rgba(255 - 70 * t, 236 - 150 * t, 180 - 150 * t);
  }
  palette[253] = rgba(150, 50, 50);
  palette[254] = rgba(25, 25, 25);
  palette[255] = rgba(140, 150, 170);

  const PATH_COLOUR = '#e0007a';
  const ROBOT_COLOURS = ['#1f77b4', '#2ca02c', '#ff7f0e', '#9467bd', '#17becf', '#8c564b'];

  const state = {
    map: null,        // name
    info: null,       // MapInfo
    version: 0,
    // The costs as images: levels[0] one pixel per cell, each next level half
    // the size, a pixel showing the most blocking cost of its 2 x 2 block, so
    // a zoomed-out large map keeps its thin walls. {w, h, cells, pixels, canvas}
    levels: [],
    overlay: null,    // offscreen canvas of expanded cells
    source: null,     // EventSource of WatchMap
    view: { scale: 1, ox: 0, oy: 0 },
    start: null,
    goal: null,
    plan: null,
    sessions: [],
    planSeq: 0,
  };

  async function api(path, options) {
    const response = await fetch(path, options);
    const body = await response.json();
    if (!response.ok) throw new Error(`${response.status}: ${body.message || response.statusText}`);
    return body;
  }

  function setStatus(text, kind) {
    const status = $('status');
    status.textContent = text;
    status.dataset.state = kind;
  }

  function showInfo() {
    const info = $('info');
    const rows = [];
    if (state.info) {
      rows.push(['map', state.map], ['size', `${state.info.width} × ${state.info.height}`],
                ['resolution', `${state.info.resolution} m`], ['version', String(state.version)]);
    }
    const p = state.plan;
    if (p) {
      rows.push(['found', p.found ? 'yes' : 'no'], ['planner', p.planner]);
      if (p.found) {
        rows.push(['length', `${Number(p.lengthM).toFixed(2)} m (${Number(p.length).toFixed(1)} cells)`],
                  ['cost', Number(p.cost).toFixed(1)]);
      } else if (p.reason) {
        rows.push(['reason', p.reason]);
      }
      rows.push(['expansions', String(p.expansions)], ['time', `${p.planningTimeUs} µs`]);
    }
    if (state.sessions.length) rows.push(['sessions', String(state.sessions.length)]);
    info.replaceChildren(...rows.flatMap(([k, v]) => {
      const dt = document.createElement('dt');
      dt.textContent = k;
      const dd = document.createElement('dd');
      dd.textContent = v;
      return [dt, dd];
    }));
    $('status').dataset.version = String(state.version);
  }

  // --- the map ------------------------------------------------------------

  function decodeBytes(base64) {
    const text = atob(base64 || '');
    const bytes = new Uint8Array(text.length);
    for (let i = 0; i < text.length; i++) bytes[i] = text.charCodeAt(i);
    return bytes;
  }

  function makeLevel(w, h) {
    const pixels = new ImageData(w, h);
    return { w, h, cells: new Uint8Array(w * h), pixels, out: new Uint32Array(pixels.data.buffer),
             canvas: new OffscreenCanvas(w, h) };
  }

  // Which of two costs a zoomed-out pixel shows: lethal over inscribed over
  // the higher cost, unknown only over free.
  const rank = (c) => (c === 255 ? 1 : c === 0 ? 0 : c + 1);

  // Recomputes the cells x0..x1, y0..y1 of level 0 in every coarser level.
  function updateLevels(x0, y0, x1, y1) {
    for (let k = 1; k < state.levels.length; k++) {
      const fine = state.levels[k - 1], coarse = state.levels[k];
      x0 >>= 1; y0 >>= 1; x1 >>= 1; y1 >>= 1;
      for (let y = y0; y <= y1; y++) {
        for (let x = x0; x <= x1; x++) {
          let best = 0, bestRank = -1;
          for (let dy = 0; dy < 2; dy++) {
            const fy = 2 * y + dy;
            if (fy >= fine.h) break;
            for (let dx = 0; dx < 2; dx++) {
              const fx = 2 * x + dx;
              if (fx >= fine.w) break;
              const c = fine.cells[fy * fine.w + fx];
              if (rank(c) > bestRank) { best = c; bestRank = rank(c); }
            }
          }
          coarse.cells[y * coarse.w + x] = best;
          coarse.out[y * coarse.w + x] = palette[best];
        }
      }
      coarse.canvas.getContext('2d').putImageData(coarse.pixels, 0, 0, x0, y0, x1 - x0 + 1, y1 - y0 + 1);
    }
  }

  function loadWholeMap(info, cells) {
    state.info = info;
    const w = info.width, h = info.height;
    const base = makeLevel(w, h);
    base.cells.set(cells.subarray(0, w * h));
    for (let i = 0; i < w * h; i++) base.out[i] = palette[base.cells[i]];
    base.canvas.getContext('2d').putImageData(base.pixels, 0, 0);
    state.levels = [base];
    for (let l = base; l.w > 256 || l.h > 256;) {
      l = makeLevel(Math.ceil(l.w / 2), Math.ceil(l.h / 2));
      state.levels.push(l);
    }
    updateLevels(0, 0, w - 1, h - 1);
    state.overlay = null;
  }

  function applyChanges(changes) {
    const base = state.levels[0];
    const g = base.canvas.getContext('2d');
    for (const change of changes) {
      const r = change.rect;
      const x0 = r.xMin || 0, y0 = r.yMin || 0, x1 = r.xMax || 0, y1 = r.yMax || 0;
      const costs = decodeBytes(change.costs);
      let k = 0;
      for (let y = y0; y <= y1; y++) {
        for (let x = x0; x <= x1; x++) {
          base.cells[y * base.w + x] = costs[k];
          base.out[y * base.w + x] = palette[costs[k++]];
        }
      }
      g.putImageData(base.pixels, 0, 0, x0, y0, x1 - x0 + 1, y1 - y0 + 1);
      updateLevels(x0, y0, x1, y1);
    }
  }

  function fitView() {
    const w = canvas.clientWidth, h = canvas.clientHeight;
    const s = Math.min(w / state.info.width, h / state.info.height) * 0.96;
    state.view = { scale: s, ox: (w - s * state.info.width) / 2, oy: (h - s * state.info.height) / 2 };
  }

  function watch(name) {
    if (state.source) state.source.close();
    const source = new EventSource(`/v1/maps/${encodeURIComponent(name)}:watch`);
    state.source = source;
    let first = true;
    source.onmessage = (message) => {
      const event = JSON.parse(message.data);
      state.version = Number(event.version);
      if (event.kind === 'MAP_EVENT_KIND_RESYNC' || event.kind === 'MAP_EVENT_KIND_REPLACED') {
        loadWholeMap(event.info, decodeBytes(event.cells));
        if (first) fitView();
        first = false;
        setStatus(`${name}: version ${state.version}`, 'ready');
      } else if (event.kind === 'MAP_EVENT_KIND_UPDATED') {
        applyChanges(event.changes || []);
        setStatus(`${name}: version ${state.version}`, 'ready');
        if (state.start && state.goal) plan();
      } else if (event.kind === 'MAP_EVENT_KIND_DELETED') {
        setStatus(`${name} was deleted`, 'error');
        source.close();
        refreshMaps();
      }
      showInfo();
      redraw();
    };
    source.addEventListener('end', (message) => {
      const status = JSON.parse(message.data);
      if (status.code !== 0) setStatus(`watch ended: ${status.message}`, 'error');
      source.close();
    });
  }

  async function selectMap(name) {
    state.map = name;
    state.start = state.goal = state.plan = null;
    state.sessions = [];
    state.version = 0;
    for (const li of $('maps').children) li.classList.toggle('selected', li.dataset.name === name);
    setStatus(`loading ${name}…`, 'loading');
    watch(name);
  }

  async function refreshMaps() {
    const list = await api('/v1/maps');
    const maps = list.maps || [];
    $('maps').replaceChildren(...maps.map((m) => {
      const li = document.createElement('li');
      li.dataset.name = m.name;
      li.innerHTML = '';
      li.append(m.name, ' ');
      const small = document.createElement('small');
      small.textContent = `${m.width}×${m.height}`;
      li.append(small);
      li.classList.toggle('selected', m.name === state.map);
      li.onclick = () => selectMap(m.name);
      return li;
    }));
    return maps;
  }

  async function loadPlanners() {
    const body = await api('/v1/planners');
    const select = $('planner');
    select.replaceChildren(...body.planners.map((p) => {
      const option = document.createElement('option');
      option.value = p.value;
      option.textContent = p.name;
      return option;
    }));
    select.value = 'PLANNER_ASTAR';
  }

  // --- planning -----------------------------------------------------------

  async function plan() {
    if (!state.map || !state.start || !state.goal) return;
    const seq = ++state.planSeq;
    const body = {
      planner: $('planner').value,
      start: { cell: state.start },
      goal: { cell: state.goal },
      options: { returnExpansions: $('expansions').checked },
    };
    setStatus('planning…', 'planning');
    try {
      const result = await api(`/v1/maps/${encodeURIComponent(state.map)}:plan`, {
        method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(body),
      });
      if (seq !== state.planSeq) return;  // a newer plan is on its way
      state.plan = result;
      drawExpanded(result.expanded || []);
      setStatus(result.found ? `planned on version ${result.mapVersion}` : `no path: ${result.reason}`,
                result.found ? 'planned' : 'no-path');
    } catch (error) {
      if (seq !== state.planSeq) return;
      state.plan = null;
      state.overlay = null;
      setStatus(error.message, 'error');
    }
    showInfo();
    redraw();
  }

  function drawExpanded(cells) {
    if (!cells.length) { state.overlay = null; return; }
    const w = state.info.width, h = state.info.height;
    const data = new ImageData(w, h);
    const out = new Uint32Array(data.buffer);
    const blue = rgba(60, 120, 220) & 0x00ffffff | (110 << 24);
    for (const c of cells) out[(c.y || 0) * w + (c.x || 0)] = blue;
    state.overlay = new OffscreenCanvas(w, h);
    state.overlay.getContext('2d').putImageData(data, 0, 0);
  }

  // --- sessions -----------------------------------------------------------

  let polls = 0;
  async function pollSessions() {
    // New and deleted maps show up in the list every few seconds.
    if (++polls % 6 === 0) refreshMaps().catch(() => {});
    if (state.map && $('robots').checked) {
      try {
        const body = await api(`/v1/maps/${encodeURIComponent(state.map)}/sessions`);
        state.sessions = body.sessions || [];
      } catch (error) {
        state.sessions = [];
      }
      showInfo();
      redraw();
    } else if (state.sessions.length) {
      state.sessions = [];
      redraw();
    }
    setTimeout(pollSessions, 500);
  }

  // --- drawing ------------------------------------------------------------

  let frame = 0;
  function redraw() {
    if (!frame) frame = requestAnimationFrame(() => { frame = 0; draw(); });
  }

  function polylineOf(plan) {
    if (plan.polyline && plan.polyline.length) return plan.polyline.map((p) => [p.x || 0, p.y || 0]);
    if (plan.poses && plan.poses.length) return plan.poses.map((p) => [p.x || 0, p.y || 0]);
    return (plan.path || []).map((c) => [(c.x || 0) + 0.5, (c.y || 0) + 0.5]);
  }

  function strokePath(points, colour, width) {
    if (points.length < 2) return;
    ctx.strokeStyle = colour;
    ctx.lineWidth = width / state.view.scale;
    ctx.lineJoin = 'round';
    ctx.beginPath();
    ctx.moveTo(points[0][0], points[0][1]);
    for (const [x, y] of points.slice(1)) ctx.lineTo(x, y);
    ctx.stroke();
  }

  function disc(x, y, radius, colour) {
    ctx.fillStyle = colour;
    ctx.beginPath();
    ctx.arc(x, y, radius, 0, 2 * Math.PI);
    ctx.fill();
  }

  function draw() {
    canvas.width = canvas.clientWidth;
    canvas.height = canvas.clientHeight;
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.fillStyle = '#ddd';
    ctx.fillRect(0, 0, canvas.width, canvas.height);
    if (!state.levels.length) return;
    const v = state.view;
    ctx.setTransform(v.scale, 0, 0, v.scale, v.ox, v.oy);
    ctx.imageSmoothingEnabled = false;
    // The finest level whose pixels are at least one screen pixel (nearest-
    // neighbour downscaling would drop thin walls).
    const k = Math.max(0, Math.min(state.levels.length - 1, Math.ceil(Math.log2(1 / v.scale) - 1e-9)));
    const level = state.levels[k];
    ctx.drawImage(level.canvas, 0, 0, level.w, level.h, 0, 0, level.w * (1 << k), level.h * (1 << k));
    if (state.overlay) ctx.drawImage(state.overlay, 0, 0);
    const px = 1 / v.scale;  // one screen pixel in cells
    state.sessions.forEach((s, i) => {
      const last = s.last;
      const colour = ROBOT_COLOURS[i % ROBOT_COLOURS.length];
      // A control session's answer: the robot at the pose it reported (the
      // command's trajectory starts there, world metres), its path only when
      // the answer carried one.
      const command = last && last.command;
      if (command && command.trajectory && command.trajectory.length) {
        const o = (state.info && state.info.origin) || {};
        const res = (state.info && state.info.resolution) || 1;
        const p = command.trajectory[0];
        if (last.plan) strokePath(polylineOf(last.plan), colour, 2);
        disc(((p.x || 0) - (o.x || 0)) / res, ((p.y || 0) - (o.y || 0)) / res,
             Math.max(0.5, 5 * px), colour);
        return;
      }
      if (!last || !last.plan) return;
      const points = polylineOf(last.plan);
      strokePath(points, colour, 2);
      const at = last.robotPose && last.robotPose.x !== undefined
        ? [last.robotPose.x, last.robotPose.y] : points[0];
      if (at) disc(at[0], at[1], Math.max(Number(last.plan.robotRadiusCells) || 0.5, 5 * px), colour);
    });
    if (state.plan && state.plan.found) strokePath(polylineOf(state.plan), PATH_COLOUR, 3);
    if (state.start) disc(state.start.x + 0.5, state.start.y + 0.5, Math.max(0.5, 5 * px), '#00a050');
    if (state.goal) disc(state.goal.x + 0.5, state.goal.y + 0.5, Math.max(0.5, 5 * px), '#d02020');
  }

  // --- input --------------------------------------------------------------

  function cellAt(clientX, clientY) {
    const r = canvas.getBoundingClientRect();
    const v = state.view;
    return { x: Math.floor((clientX - r.left - v.ox) / v.scale),
             y: Math.floor((clientY - r.top - v.oy) / v.scale) };
  }

  function onMap(cell) {
    return state.info && cell.x >= 0 && cell.y >= 0 && cell.x < state.info.width && cell.y < state.info.height;
  }

  let drag = null;
  canvas.addEventListener('mousedown', (e) => {
    drag = { x: e.clientX, y: e.clientY, ox: state.view.ox, oy: state.view.oy, moved: false };
  });
  window.addEventListener('mousemove', (e) => {
    if (state.info) {
      const c = cellAt(e.clientX, e.clientY);
      const o = state.info.origin || {};
      const res = state.info.resolution || 1;
      $('cursor').textContent = onMap(c)
        ? `cell (${c.x}, ${c.y})  world (${((o.x || 0) + (c.x + 0.5) * res).toFixed(2)}, ` +
          `${((o.y || 0) + (c.y + 0.5) * res).toFixed(2)}) m` : '';
    }
    if (!drag) return;
    const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    if (Math.abs(dx) + Math.abs(dy) > 4) drag.moved = true;
    if (drag.moved) {
      state.view.ox = drag.ox + dx;
      state.view.oy = drag.oy + dy;
      redraw();
    }
  });
  window.addEventListener('mouseup', (e) => {
    const d = drag;
    drag = null;
    if (!d || d.moved || e.target !== canvas || !state.info) return;
    const cell = cellAt(e.clientX, e.clientY);
    if (!onMap(cell)) return;
    if (!state.start || state.goal) {
      state.start = cell;
      state.goal = null;
      state.plan = null;
      state.overlay = null;
      setStatus('now click a goal', 'ready');
    } else {
      state.goal = cell;
      plan();
    }
    showInfo();
    redraw();
  });
  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    const r = canvas.getBoundingClientRect();
    const mx = e.clientX - r.left, my = e.clientY - r.top;
    const factor = Math.exp(-e.deltaY * 0.0015);
    const v = state.view;
    const scale = Math.min(64, Math.max(0.02, v.scale * factor));
    v.ox = mx - (mx - v.ox) * (scale / v.scale);
    v.oy = my - (my - v.oy) * (scale / v.scale);
    v.scale = scale;
    redraw();
  }, { passive: false });
  window.addEventListener('resize', redraw);
  $('clear').onclick = () => {
    state.start = state.goal = state.plan = state.overlay = null;
    showInfo();
    redraw();
  };
  $('planner').onchange = () => plan();
  $('expansions').onchange = () => plan();
  $('robots').onchange = () => redraw();

  // For tests and the console: where a cell's centre is on the page.
  window.pathdViewer = {
    state,
    cellToClient(x, y) {
      const r = canvas.getBoundingClientRect();
      const v = state.view;
      return { x: r.left + v.ox + (x + 0.5) * v.scale, y: r.top + v.oy + (y + 0.5) * v.scale };
    },
    selectMap,
    redraw,
    PATH_COLOUR,
  };

  (async () => {
    try {
      await loadPlanners();
      const maps = await refreshMaps();
      const wanted = new URLSearchParams(location.search).get('map');
      const first = maps.find((m) => m.name === wanted) || maps[0];
      if (first) selectMap(first.name); else setStatus('no maps on this pathd', 'idle');
    } catch (error) {
      setStatus(error.message, 'error');
    }
    pollSessions();
  })();
})();
