// The report page: 3D replay of one simulated run (robot from Leju's meshes posed by the
// model's own kinematic tree, human skeleton, ground, support polygon, ZMP, contact forces),
// a timeline with repairs / pushes / the fall, plots with a cursor linked to it, and the
// report's tables. Data come from data/*.js (written by `kuavo demo` / `kuavo replay`).
// window.KUAVO_VIEW is the page's state for the browser test (tests/report/html_report_test.py).
(function () {
  "use strict";
  const K = window.KUAVO;
  const report = K.report, model = K.model;
  const $ = (id) => document.getElementById(id);
  const started_ms = performance.now();

  // ---- binary data -------------------------------------------------------------------------
  function decodeBase64(text) {
    const bin = atob(text);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    return bytes.buffer;
  }
  // tools/report/mesh_decimate.h: encode_mesh.
  function decodeMesh(text) {
    const buf = decodeBase64(text);
    const dv = new DataView(buf);
    const nv = dv.getUint32(0, true), nt = dv.getUint32(4, true);
    const c = [dv.getFloat32(8, true), dv.getFloat32(12, true), dv.getFloat32(16, true)];
    const step = dv.getFloat32(20, true);
    const q = new Int16Array(buf, 24, 3 * nv);
    const pos = new Float32Array(3 * nv);
    for (let i = 0; i < 3 * nv; i++) pos[i] = c[i % 3] + step * q[i];
    const at = (24 + 6 * nv + 3) & ~3;
    const index = nv > 65535 ? new Uint32Array(buf, at, 3 * nt) : new Uint16Array(buf, at, 3 * nt);
    const g = new THREE.BufferGeometry();
    g.setAttribute("position", new THREE.BufferAttribute(pos, 3));
    g.setIndex(new THREE.BufferAttribute(index, 1));
    g.computeVertexNormals();
    return g;
  }

  // ---- scene -------------------------------------------------------------------------------
  const view = $("view3d");
  const renderer = new THREE.WebGLRenderer({ antialias: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  view.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xeef2f6);
  const camera = new THREE.PerspectiveCamera(40, 1, 0.05, 100);
  camera.up.set(0, 0, 1);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x667788, 1.6));
  const sun = new THREE.DirectionalLight(0xffffff, 1.8);
  sun.position.set(3, -4, 6);
  scene.add(sun);
  const ground = new THREE.Mesh(new THREE.PlaneGeometry(40, 40), new THREE.MeshLambertMaterial({ color: 0xd9dde2 }));
  scene.add(ground);
  const grid = new THREE.GridHelper(40, 80, 0x9aa3ad, 0xb8c0c8);
  grid.rotation.x = Math.PI / 2;  // GridHelper lies in x-z; the world is z up
  grid.position.z = 0.001;
  scene.add(grid);

  // The robot: per body a fixed joint frame (origin, rotation) under its parent and a moving
  // frame turned about the joint axis by q; the meshes hang under the moving frames.
  const robotMaterial = new THREE.MeshStandardMaterial({ color: 0xb9c0c8, metalness: 0.15, roughness: 0.6, flatShading: true, side: THREE.DoubleSide });
  const darkMaterial = new THREE.MeshStandardMaterial({ color: 0x3a4048, metalness: 0.2, roughness: 0.6, flatShading: true, side: THREE.DoubleSide });
  const geometries = {};
  const geometry = (name) => (geometries[name] = geometries[name] || decodeMesh(K.meshes[name]));
  function poseOf(obj, j) {
    const R = j.R, p = j.p;
    const m = new THREE.Matrix4().set(R[0], R[1], R[2], p[0], R[3], R[4], R[5], p[1], R[6], R[7], R[8], p[2], 0, 0, 0, 1);
    m.decompose(obj.position, obj.quaternion, obj.scale);
  }
  function attachVisual(parent, v, dark) {
    if (!v || !K.meshes[v.mesh]) return;
    const mesh = new THREE.Mesh(geometry(v.mesh), dark ? darkMaterial : robotMaterial);
    poseOf(mesh, v);
    parent.add(mesh);
  }
  const robot = new THREE.Group();
  scene.add(robot);
  const bodies = [], axes = [];
  model.bodies.forEach((b, i) => {
    const joint = new THREE.Group();
    const body = new THREE.Group();
    if (b.parent >= 0) poseOf(joint, b);
    joint.add(body);
    (b.parent >= 0 ? bodies[b.parent] : robot).add(joint);
    bodies.push(body);
    axes.push(new THREE.Vector3(b.axis[0], b.axis[1], b.axis[2]));
    attachVisual(body, b.visual, /leg_[lr][56]|zarm_[lr][67]/.test(b.name));
  });
  const contactFrames = [];
  model.frames.forEach((f, i) => {
    const holder = new THREE.Group();
    poseOf(holder, f);
    bodies[f.body].add(holder);
    attachVisual(holder, f.visual, true);
    if (i < model.contact_points) contactFrames.push(holder);
  });
  const tmpQ = new THREE.Quaternion();
  function setPose(base, quat, q) {
    robot.position.set(base[0], base[1], base[2]);
    robot.quaternion.set(quat[0], quat[1], quat[2], quat[3]);
    for (let b = 1; b < bodies.length; b++) bodies[b].quaternion.copy(tmpQ.setFromAxisAngle(axes[b], q[b - 1]));
    robot.updateMatrixWorld(true);
  }
  // The check pose exported with the model: this page's FK must agree with controllers/dynamics.
  (function checkKinematics() {
    const c = model.fk_check, q = c.q;
    setPose(q.slice(0, 3), q.slice(3, 7), q.slice(7));
    let worst = 0;
    const w = new THREE.Vector3();
    c.body_positions_m.forEach((p, b) => {
      bodies[b].getWorldPosition(w);
      worst = Math.max(worst, Math.hypot(w.x - p[0], w.y - p[1], w.z - p[2]));
    });
    if (!(worst < 1e-4)) console.error("kuavo report: forward kinematics disagree with the model by " + worst + " m");
    K.fk_error_m = worst;
  })();

  // Overlays: ZMP, support polygon, contact forces, human skeleton.
  const zmpDot = new THREE.Mesh(new THREE.CylinderGeometry(0.025, 0.025, 0.004, 24), new THREE.MeshBasicMaterial({ color: 0xd62728 }));
  zmpDot.rotation.x = Math.PI / 2;
  scene.add(zmpDot);
  const polyGeom = new THREE.BufferGeometry();
  polyGeom.setAttribute("position", new THREE.BufferAttribute(new Float32Array(3 * 9), 3));
  const poly = new THREE.LineLoop(polyGeom, new THREE.LineBasicMaterial({ color: 0x2ca02c }));
  scene.add(poly);
  const arrows = contactFrames.map(() => {
    const a = new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(), 0.1, 0xff7f0e, 0.04, 0.025);
    scene.add(a);
    return a;
  });
  const kForceScale_m_per_N = 1 / 600;  // a standing foot corner (~135 N) draws 0.22 m
  const kFootLoaded_N = 20;             // as sim/motion_loop.cpp: a foot counts in the support above this
  const human = K.human;
  let humanLines = null, humanPoints = null;  // bones, and the keypoints as dots
  if (human) {
    const g = new THREE.BufferGeometry();
    g.setAttribute("position", new THREE.BufferAttribute(new Float32Array(6 * human.bones.length), 3));
    humanLines = new THREE.LineSegments(g, new THREE.LineBasicMaterial({ color: 0x1f77b4, transparent: true, opacity: 0.85 }));
    humanLines.frustumCulled = false;
    scene.add(humanLines);
    const gp = new THREE.BufferGeometry();
    gp.setAttribute("position", new THREE.BufferAttribute(new Float32Array(3 * human.names.length), 3));
    humanPoints = new THREE.Points(gp, new THREE.PointsMaterial({ color: 0x1f77b4, size: 7, sizeAttenuation: false, transparent: true }));
    humanPoints.frustumCulled = false;
    scene.add(humanPoints);
    human.frames_f32 = new Float32Array(decodeBase64(human.data));
  }
  const kHumanBeside_m = 0.9;  // "beside": the skeleton walks 0.9 m to the robot's left

  // ---- camera: orbit around the robot, following it --------------------------------------
  const orbit = { azimuth: -0.9, elevation: 0.3, distance: 3.4, target: new THREE.Vector3(0, 0, 0.8) };
  function placeCamera() {
    const t = orbit.target, d = orbit.distance;
    camera.position.set(t.x + d * Math.cos(orbit.elevation) * Math.cos(orbit.azimuth),
                        t.y + d * Math.cos(orbit.elevation) * Math.sin(orbit.azimuth), t.z + d * Math.sin(orbit.elevation));
    camera.lookAt(t);
  }
  let drag = null;
  renderer.domElement.addEventListener("pointerdown", (e) => { drag = { x: e.clientX, y: e.clientY }; });
  window.addEventListener("pointerup", () => { drag = null; });
  window.addEventListener("pointermove", (e) => {
    if (!drag) return;
    orbit.azimuth -= 0.01 * (e.clientX - drag.x);
    orbit.elevation = Math.min(1.4, Math.max(-0.1, orbit.elevation + 0.01 * (e.clientY - drag.y)));
    drag = { x: e.clientX, y: e.clientY };
    render();
  });
  renderer.domElement.addEventListener("wheel", (e) => {
    e.preventDefault();
    orbit.distance = Math.min(15, Math.max(1, orbit.distance * Math.exp(0.001 * e.deltaY)));
    render();
  }, { passive: false });

  // ---- runs --------------------------------------------------------------------------------
  let run = null;     // { meta, L (layout), n, data: Float32Array }
  let t_s = 0, playing = false, speed = 1, joint = 3;
  const runSelect = $("run");
  report.runs.forEach((r, i) => {
    const o = document.createElement("option");
    o.value = i;
    o.textContent = r.name + (r.fell ? " (fell)" : "");
    runSelect.appendChild(o);
  });
  model.joints.forEach((j, i) => {
    const o = document.createElement("option");
    o.value = i;
    o.textContent = j.name;
    $("joint").appendChild(o);
  });
  $("joint").value = joint;

  function loadRun(index, done) {
    const meta = report.runs[index];
    const ready = () => {
      const raw = K.runs[meta.name];
      run = { meta, L: raw.layout, n: raw.frames, data: new Float32Array(decodeBase64(raw.data)) };
      t_s = 0;
      $("run-description").textContent = meta.name + ": " + meta.description;
      buildPlots();
      drawTimeline();
      update();
      if (done) done();
    };
    if (K.runs[meta.name]) return ready();
    const s = document.createElement("script");  // loaded on demand: a page with many runs opens fast
    s.src = meta.file;
    s.onload = ready;
    s.onerror = () => console.error("kuavo report: cannot load " + meta.file);
    document.head.appendChild(s);
  }
  const frameAt = (t) => Math.max(0, Math.min(run.n - 1, Math.round(t * run.meta.rate_hz)));
  const ch = (f, k) => run.data[f * run.L.size + k];
  function channel(k) {
    const out = new Float32Array(run.n);
    for (let f = 0; f < run.n; f++) out[f] = ch(f, k);
    return out;
  }
  const time = () => channel(run.L.time);

  // ---- plots (canvas 2D, with a cursor at the replay's time) -------------------------------
  let plots = [];
  function buildPlots() {
    const L = run.L, box = $("plots");
    box.innerHTML = "";
    const jn = model.joints[joint];
    const limit = jn.peak_torque_Nm;
    const tauJ = channel(L.tau + joint).map((v) => Math.abs(v) / limit);
    plots = [
      { id: "plot-tracking", title: "joint tracking: " + jn.name + " [rad]", series: [
          { y: channel(L.qref + joint), color: "#7f7f7f", dash: true, name: "plan" },
          { y: channel(L.q + joint), color: "#1f77b4", name: "simulated" }],
        lines: [{ y: jn.min_rad, color: "#d62728" }, { y: jn.max_rad, color: "#d62728" }] },
      { id: "plot-com", title: "CoM [m] (dashed: plan)", series: [0, 1, 2].flatMap((a) => [
          { y: channel(L.comref + a), color: ["#1f77b4", "#2ca02c", "#9467bd"][a], dash: true },
          { y: channel(L.com + a), color: ["#1f77b4", "#2ca02c", "#9467bd"][a], name: "xyz"[a] }]) },
      { id: "plot-margin", title: "ZMP margin to the support polygon's edge [m] (min per frame)",
        series: [{ y: channel(L.margin), color: "#d62728", name: "margin" }], lines: [{ y: 0, color: "#333" }] },
      { id: "plot-torque", title: "joint torque / peak limit: all joints (max) and " + jn.name,
        series: [{ y: channel(L.tau_ratio), color: "#ff7f0e", name: "max over joints" }, { y: tauJ, color: "#1f77b4", name: jn.name }],
        lines: [{ y: 1, color: "#d62728" }] },
    ];
    const t = time();
    for (const p of plots) {
      const c = document.createElement("canvas");
      c.id = p.id;
      box.appendChild(c);
      p.canvas = c;
      p.t = t;
      let lo = Infinity, hi = -Infinity;
      for (const s of p.series) for (const v of s.y) if (isFinite(v)) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
      for (const l of p.lines || []) if (isFinite(lo)) { lo = Math.min(lo, l.y); hi = Math.max(hi, l.y); }
      if (!isFinite(lo)) { lo = -1; hi = 1; p.empty = true; }
      if (hi - lo < 1e-6) { lo -= 0.5; hi += 0.5; }
      p.lo = lo - 0.05 * (hi - lo); p.hi = hi + 0.05 * (hi - lo);
      const scrubAt = (e) => { const r = c.getBoundingClientRect(); seek((e.clientX - r.left - p.x0) / (r.width - p.x0 - 6) * run.meta.duration_s); };
      c.addEventListener("pointerdown", (e) => { scrubAt(e); c.onpointermove = scrubAt; });
      c.addEventListener("pointerup", () => { c.onpointermove = null; });
      p.background = null;
    }
    drawPlots(true);
  }
  function drawPlots(full) {
    for (const p of plots) {
      const c = p.canvas, dpr = window.devicePixelRatio || 1;
      const w = c.clientWidth, h = c.clientHeight;
      if (full || c.width !== Math.round(w * dpr)) {
        c.width = Math.round(w * dpr); c.height = Math.round(h * dpr);
        const g = c.getContext("2d", { willReadFrequently: true });
        g.setTransform(dpr, 0, 0, dpr, 0, 0);
        g.clearRect(0, 0, w, h);
        p.x0 = 46;
        const X = (t) => p.x0 + (w - p.x0 - 6) * t / run.meta.duration_s;
        const Y = (v) => 16 + (h - 30) * (1 - (v - p.lo) / (p.hi - p.lo));
        g.font = "11px system-ui, sans-serif"; g.fillStyle = "#222";
        g.fillText(p.title + (p.empty ? " — not in this log" : ""), p.x0, 11);
        g.fillStyle = "#666";
        g.fillText(p.hi.toPrecision(3), 2, 22); g.fillText(p.lo.toPrecision(3), 2, h - 14);
        g.fillText("0", p.x0, h - 2); g.fillText(run.meta.duration_s.toFixed(1) + " s", w - 40, h - 2);
        for (const l of p.lines || []) {
          g.strokeStyle = l.color; g.globalAlpha = 0.5; g.setLineDash([2, 3]);
          g.beginPath(); g.moveTo(p.x0, Y(l.y)); g.lineTo(w - 6, Y(l.y)); g.stroke();
        }
        g.globalAlpha = 1;
        for (const s of p.series) {
          g.strokeStyle = s.color; g.setLineDash(s.dash ? [4, 3] : []); g.lineWidth = 1.2;
          g.beginPath();
          let pen = false;
          for (let f = 0; f < s.y.length; f++) {
            const v = s.y[f];
            if (!isFinite(v)) { pen = false; continue; }
            pen ? g.lineTo(X(p.t[f]), Y(v)) : g.moveTo(X(p.t[f]), Y(v));
            pen = true;
          }
          g.stroke();
        }
        g.setLineDash([]);
        for (const m of run.meta.marks) {
          if (m.kind !== "fall") continue;
          g.strokeStyle = "#d62728"; g.lineWidth = 2;
          g.beginPath(); g.moveTo(X(m.start_s), 14); g.lineTo(X(m.start_s), h - 12); g.stroke();
        }
        p.background = g.getImageData(0, 0, c.width, c.height);
        p.X = X;
      }
      const g = c.getContext("2d", { willReadFrequently: true });
      g.putImageData(p.background, 0, 0);
      p.cursor_px = p.X(t_s);
      g.strokeStyle = "#000"; g.lineWidth = 1;
      g.beginPath(); g.moveTo(p.cursor_px, 14); g.lineTo(p.cursor_px, h - 12); g.stroke();
    }
  }

  // ---- timeline: repairs, pushes, the fall ---------------------------------------------------
  const kMarkColor = { repair: "rgba(255,127,14,0.55)", push: "#9467bd", fall: "#d62728" };
  function drawTimeline() {
    const c = $("timeline"), dpr = window.devicePixelRatio || 1, w = c.clientWidth, h = c.clientHeight;
    c.width = Math.round(w * dpr); c.height = Math.round(h * dpr);
    const g = c.getContext("2d", { willReadFrequently: true });
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    g.fillStyle = "#e3e7ec"; g.fillRect(0, 8, w, 18);
    const X = (t) => w * t / run.meta.duration_s;
    const box = $("timeline-box");
    box.querySelectorAll(".mark").forEach((e) => e.remove());
    for (const m of run.meta.marks) {
      g.fillStyle = kMarkColor[m.kind] || "#888";
      const x0 = X(m.start_s), x1 = Math.max(X(m.end_s), x0 + (m.kind === "fall" ? 3 : 2));
      g.fillRect(x0, m.kind === "repair" ? 8 : 2, x1 - x0, m.kind === "repair" ? 18 : 30);
      // A DOM element per mark too: hover shows its reason (and tests can find the fall).
      const d = document.createElement("div");
      d.className = "mark mark-" + m.kind;
      d.title = m.label;
      d.dataset.start_s = m.start_s;
      d.style.cssText = `position:absolute;top:0;height:34px;left:${(100 * m.start_s / run.meta.duration_s).toFixed(3)}%;width:${Math.max(0.3, 100 * (m.end_s - m.start_s) / run.meta.duration_s).toFixed(3)}%;pointer-events:none`;
      box.appendChild(d);
      if (m.kind === "fall") { g.fillStyle = "#d62728"; g.font = "bold 11px system-ui"; g.fillText("fall", Math.min(x0 + 4, w - 24), 22); }
    }
    timelineBase = g.getImageData(0, 0, c.width, c.height);
  }
  let timelineBase = null;
  function drawTimelineCursor() {
    const c = $("timeline"), g = c.getContext("2d", { willReadFrequently: true }), w = c.clientWidth;
    g.putImageData(timelineBase, 0, 0);
    const x = w * t_s / run.meta.duration_s;
    g.fillStyle = "#1d232b"; g.fillRect(x - 1, 0, 2, 34);
  }

  // ---- one frame -----------------------------------------------------------------------------
  const v3 = new THREE.Vector3();
  function cross(o, a, b) { return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]); }
  function hull(pts) {  // Andrew's monotone chain
    pts.sort((a, b) => a[0] - b[0] || a[1] - b[1]);
    const lower = [], upper = [];
    for (const p of pts) { while (lower.length >= 2 && cross(lower[lower.length - 2], lower[lower.length - 1], p) <= 0) lower.pop(); lower.push(p); }
    for (const p of pts.slice().reverse()) { while (upper.length >= 2 && cross(upper[upper.length - 2], upper[upper.length - 1], p) <= 0) upper.pop(); upper.push(p); }
    return lower.slice(0, -1).concat(upper.slice(0, -1));
  }
  function update() {
    const L = run.L, f = frameAt(t_s), o = f * L.size, d = run.data;
    setPose([d[o + L.base], d[o + L.base + 1], d[o + L.base + 2]],
            [d[o + L.quat], d[o + L.quat + 1], d[o + L.quat + 2], d[o + L.quat + 3]], d.subarray(o + L.q, o + L.q + model.joints.length));
    // Contact forces at the sole corners; the loaded feet's corners make the support polygon.
    const corners = [], cop = [0, 0, 0];
    const perFoot = contactFrames.length / 2;
    for (let foot = 0; foot < 2; foot++) {
      let fz = 0;
      for (let c = foot * perFoot; c < (foot + 1) * perFoot; c++) fz += d[o + L.force + 3 * c + 2];
      for (let c = foot * perFoot; c < (foot + 1) * perFoot; c++) {
        contactFrames[c].getWorldPosition(v3);
        const fx = d[o + L.force + 3 * c], fy = d[o + L.force + 3 * c + 1], fzc = d[o + L.force + 3 * c + 2];
        const mag = Math.hypot(fx, fy, fzc), a = arrows[c];
        a.visible = $("show-forces").checked && mag > 5;
        if (a.visible) {
          a.position.copy(v3);
          a.setDirection(new THREE.Vector3(fx / mag, fy / mag, fzc / mag));
          a.setLength(Math.max(0.06, mag * kForceScale_m_per_N), 0.04, 0.025);
        }
        if (fz >= kFootLoaded_N) { corners.push([v3.x, v3.y]); cop[0] += fzc * v3.x; cop[1] += fzc * v3.y; cop[2] += fzc; }
      }
    }
    const h = corners.length >= 3 ? hull(corners) : [];
    const pa = polyGeom.attributes.position;
    for (let i = 0; i < 9; i++) { const p = h[Math.min(i, h.length - 1)] || [0, 0]; pa.setXYZ(i, p[0], p[1], 0.003); }
    pa.needsUpdate = true;
    polyGeom.setDrawRange(0, h.length);
    poly.visible = h.length >= 3;
    // The ZMP: the log's centre of pressure, or the one of the forces when the log has none.
    let zx = d[o + L.zmp], zy = d[o + L.zmp + 1];
    if (!isFinite(zx) && cop[2] > 50) { zx = cop[0] / cop[2]; zy = cop[1] / cop[2]; }
    zmpDot.visible = isFinite(zx) && isFinite(zy);
    if (zmpDot.visible) zmpDot.position.set(zx, zy, 0.004);
    robot.visible = $("show-robot").checked;
    // The human: its own clock starts where the robot's motion leaves the lead-in.
    if (humanLines) {
      const mode = $("human-mode").value;
      const hf = Math.round((t_s - human.t0_s) * human.rate_hz);
      humanLines.visible = humanPoints.visible = run.meta.human && mode !== "off" && hf >= 0 && hf < human.frames;
      if (humanLines.visible) {
        const nk = human.names.length, src = human.frames_f32, dst = humanLines.geometry.attributes.position;
        const dy = mode === "beside" ? kHumanBeside_m : 0;
        humanLines.material.opacity = mode === "over" ? 0.6 : 0.9;
        const pts = humanPoints.geometry.attributes.position;
        for (let k = 0; k < nk; k++) pts.setXYZ(k, src[(hf * nk + k) * 3], src[(hf * nk + k) * 3 + 1] + dy, src[(hf * nk + k) * 3 + 2]);
        pts.needsUpdate = true;
        humanPoints.material.opacity = humanLines.material.opacity;
        human.bones.forEach(([a, b], i) => {
          dst.setXYZ(2 * i, src[(hf * nk + a) * 3], src[(hf * nk + a) * 3 + 1] + dy, src[(hf * nk + a) * 3 + 2]);
          dst.setXYZ(2 * i + 1, src[(hf * nk + b) * 3], src[(hf * nk + b) * 3 + 1] + dy, src[(hf * nk + b) * 3 + 2]);
        });
        dst.needsUpdate = true;
      }
    }
    // The camera follows the robot (between it and the skeleton's lane when the run has one; the
    // view does not jump when the skeleton is shown or hidden).
    orbit.target.set(d[o + L.base], d[o + L.base + 1] + (run.meta.human ? kHumanBeside_m / 2 : 0), 0.75);
    $("clock").textContent = t_s.toFixed(2) + " / " + run.meta.duration_s.toFixed(2) + " s";
    $("scrub").value = Math.round(1000 * t_s / run.meta.duration_s);
    drawTimelineCursor();
    drawPlots(false);
    render();
  }
  function render() {
    const w = view.clientWidth, h = view.clientHeight;
    if (renderer.domElement.width !== Math.round(w * renderer.getPixelRatio())) {
      renderer.setSize(w, h);
      camera.aspect = w / h;
      camera.updateProjectionMatrix();
    }
    placeCamera();
    renderer.render(scene, camera);
  }
  function seek(t) {
    if (!run) return;
    t_s = Math.max(0, Math.min(run.meta.duration_s, t));
    update();
  }

  // ---- controls and playback ----------------------------------------------------------------
  $("scrub").addEventListener("input", (e) => seek(e.target.value / 1000 * run.meta.duration_s));
  $("play").addEventListener("click", () => {
    playing = !playing;
    $("play").textContent = playing ? "Pause" : "Play";
    if (playing && t_s >= run.meta.duration_s) t_s = 0;
    last_ms = null;
    if (playing) requestAnimationFrame(tick);
  });
  $("speed").addEventListener("change", (e) => { speed = Number(e.target.value); });
  runSelect.addEventListener("change", (e) => loadRun(Number(e.target.value)));
  $("joint").addEventListener("change", (e) => { joint = Number(e.target.value); buildPlots(); update(); });
  for (const id of ["show-robot", "show-forces", "human-mode"]) $(id).addEventListener("change", () => update());
  window.addEventListener("resize", () => { drawTimeline(); drawPlots(true); update(); });
  let last_ms = null;
  function tick(now) {
    if (!playing) return;
    if (last_ms !== null) t_s += speed * (now - last_ms) / 1000;
    last_ms = now;
    if (t_s >= run.meta.duration_s) {
      t_s = run.meta.duration_s;
      playing = false;
      $("play").textContent = "Play";
    }
    update();
    if (playing) requestAnimationFrame(tick);
  }

  // ---- the report's tables, figures and text -------------------------------------------------
  $("title").textContent = report.title;
  $("subtitle").textContent = report.subtitle;
  document.title = report.title;
  for (const t of report.tables) {
    const sec = $("tables");
    const h = document.createElement("h2"); h.textContent = t.title; sec.appendChild(h);
    const table = document.createElement("table");
    const tr = table.insertRow();
    for (const c of t.header) { const th = document.createElement("th"); th.textContent = c; tr.appendChild(th); }
    for (const r of t.rows) { const row = table.insertRow(); for (const c of r) row.insertCell().textContent = c.replace(/\*\*/g, ""); }
    sec.appendChild(table);
    if (t.note) { const p = document.createElement("p"); p.textContent = t.note; sec.appendChild(p); }
  }
  for (const f of report.figures) {
    const fig = document.createElement("figure");
    const img = document.createElement("img"); img.src = f.file; img.alt = f.caption;
    const cap = document.createElement("figcaption"); cap.textContent = f.caption;
    fig.appendChild(img); fig.appendChild(cap); $("figures").appendChild(fig);
  }
  for (const b of report.text_blocks) {
    const h = document.createElement("h3"); h.textContent = b.title;
    const pre = document.createElement("pre"); pre.textContent = b.text;
    $("texts").appendChild(h); $("texts").appendChild(pre);
  }

  window.KUAVO_VIEW = {
    ready: false,
    seek,
    selectRun(i, done) { runSelect.value = i; loadRun(i, done); },
    state() {
      const f = frameAt(t_s);
      return { t_s, frame: f, run: run.meta.name, base: [0, 1, 2].map((k) => ch(f, run.L.base + k)),
               cursor_px: plots.map((p) => p.cursor_px), fk_error_m: K.fk_error_m };
    },
  };
  if (report.runs.length === 0) {
    console.error("kuavo report: no runs");
    return;
  }
  loadRun(0, () => {
    window.KUAVO_VIEW.ready = true;
    window.KUAVO_VIEW.ready_ms = performance.now() - started_ms;
    window.KUAVO_VIEW.load_ms = performance.now();  // since navigation start
  });
})();
