// scanplan's 3D replay viewer (OUT/replay.html): the cell animated over the planned motion.
// Reads the JSON in #scanplan-data (written by cli/io/replay_html.cpp); needs THREE and
// THREE.OrbitControls. World frame: z up, metres. window.scanplanReplay lets tests drive it.
(function () {
  'use strict';
  const D = JSON.parse(document.getElementById('scanplan-data').textContent);

  function bytes(b64) {
    const bin = atob(b64);
    const out = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; ++i) out[i] = bin.charCodeAt(i);
    return out;
  }
  const f32 = (b64) => new Float32Array(bytes(b64).buffer);
  const u32 = (b64) => new Uint32Array(bytes(b64).buffer);

  // Renderer, camera, lights.
  const view = document.getElementById('view');
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  view.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf2f2f2);
  const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 50);
  camera.up.set(0, 0, 1);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x8899aa, 1.6));
  const sun = new THREE.DirectionalLight(0xffffff, 1.6);
  sun.position.set(1.5, -2, 3);
  scene.add(sun);
  const grid = new THREE.GridHelper(2, 20, 0xbbbbbb, 0xdddddd);
  grid.rotation.x = Math.PI / 2;
  grid.position.z = D.floor;  // under the lowest body
  scene.add(grid);
  scene.add(new THREE.AxesHelper(0.2));

  // The carriers: robot links 0..6, the scanner's laser frame, the table top; world bodies.
  const carriers = [];
  for (let k = 0; k < 9; ++k) {
    const g = new THREE.Group();
    g.matrixAutoUpdate = false;
    scene.add(g);
    carriers.push(g);
  }
  const colourOf = (name, frame) =>
    name === 'scanner' ? 0x333a44 : name === 'table' ? 0x9a9a9a : name === 'part' ? 0xcccccc
      : frame >= 0 && frame <= 6 ? 0xf39c34 : 0x7f93a8;
  const meshes = {}, bodyMeshes = [], standins = [];  // by name; in D.bodies' order
  for (const b of D.bodies) {
    const g = new THREE.BufferGeometry();
    const v = f32(b.vertices), t = u32(b.triangles);
    if (b.colours) {  // per triangle (sRGB): unshared vertices carry the triangle's colour
      const c = bytes(b.colours), rgb = new THREE.Color();
      const pos = new Float32Array(t.length * 3), col = new Float32Array(t.length * 3);
      for (let i = 0; i < t.length; ++i) {
        const k = 3 * Math.floor(i / 3);
        rgb.setRGB(c[k] / 255, c[k + 1] / 255, c[k + 2] / 255, THREE.SRGBColorSpace);
        for (let a = 0; a < 3; ++a) pos[3 * i + a] = v[3 * t[i] + a];
        col[3 * i] = rgb.r; col[3 * i + 1] = rgb.g; col[3 * i + 2] = rgb.b;
      }
      g.setAttribute('position', new THREE.BufferAttribute(pos, 3));
      g.setAttribute('color', new THREE.BufferAttribute(col, 3));
    } else {
      g.setAttribute('position', new THREE.BufferAttribute(v, 3));
      g.setIndex(new THREE.BufferAttribute(t, 1));
    }
    g.computeVertexNormals();
    const m = new THREE.MeshStandardMaterial({
      color: b.colours ? 0xffffff : colourOf(b.name, b.frame), vertexColors: !!b.colours,
      roughness: 0.7, metalness: 0.05, flatShading: !!b.colours, side: THREE.DoubleSide,
    });
    const mesh = new THREE.Mesh(g, m);
    meshes[b.name] = mesh;
    bodyMeshes.push(mesh);
    (b.frame >= 0 ? carriers[b.frame] : scene).add(mesh);
    if (b.standin) {  // a link's stand-in in the maps: over its mesh, see-through, on request
      m.transparent = true;
      m.opacity = 0.55;
      m.depthWrite = false;
      mesh.visible = false;
      standins.push(mesh);
    }
  }
  const standinBox = document.getElementById('standins');
  if (standinBox) {
    standinBox.addEventListener('change', () => {
      for (const mesh of standins) mesh.visible = standinBox.checked;
      render();
    });
  }

  // The part's coverage as it grows: a triangle keeps its final colour (points/mm², viridis) from
  // the time the first cloud point lands on it (covered_t), light grey before; the triangles never
  // covered turn red-orange at the last frame. Triangles sorted by that time: a frame change
  // repaints only those whose state changed.
  const kUntouched = new THREE.Color(0xd0d0d0);
  function growingCoverage(body, mesh) {
    const colour = mesh.geometry.getAttribute('color');
    const final = colour.array.slice();
    const count = final.length / 9;
    const at = body.covered_t ? f32(body.covered_t) : new Float32Array(count).fill(-Infinity);
    const order = new Uint32Array(count).map((_, i) => i).sort((a, b) => at[a] - at[b]);
    const sorted = Float32Array.from(order, (i) => at[i]);
    const finite = sorted.findIndex((x) => x === Infinity);
    const covered = finite < 0 ? count : finite;
    const paint = (tri, on) => {
      for (let k = 9 * tri; k < 9 * tri + 9; k += 3) {
        colour.array[k] = on ? final[k] : kUntouched.r;
        colour.array[k + 1] = on ? final[k + 1] : kUntouched.g;
        colour.array[k + 2] = on ? final[k + 2] : kUntouched.b;
      }
    };
    let shown = 0, ended = false;
    for (let i = 0; i < count; ++i) paint(i, false);
    const update = (t, end) => {
      const want = Math.min(upperBound(sorted, t), covered);
      if (want === shown && end === ended) return;
      while (shown < want) paint(order[shown++], true);
      while (shown > want) paint(order[--shown], false);
      if (end !== ended) for (let j = covered; j < count; ++j) paint(order[j], end);
      ended = end;
      colour.needsUpdate = true;
    };
    return { update, coloured: () => shown };
  }
  const partBody = D.bodies.find((b) => b.name === 'part' && b.colours);
  const coverage = partBody ? growingCoverage(partBody, meshes.part)
    : { update: () => {}, coloured: () => 0 };

  // The part frame on the table top: the cloud and the uncovered samples live there.
  const partFrame = new THREE.Group();
  partFrame.matrixAutoUpdate = false;
  partFrame.matrix.fromArray(D.X_RP);
  carriers[8].add(partFrame);
  const cloudGeometry = new THREE.BufferGeometry();
  cloudGeometry.setAttribute('position', new THREE.BufferAttribute(f32(D.cloud), 3));
  const cloud = new THREE.Points(cloudGeometry,
    new THREE.PointsMaterial({ color: 0x1f5fbf, size: 0.0012, sizeAttenuation: true }));
  cloud.frustumCulled = false;
  partFrame.add(cloud);
  const cloudT = f32(D.cloud_t);
  // The cloud shows the last kTrail seconds' points (the coverage colours keep the rest), or all
  // of them up to now when the legend's checkbox says so.
  const kTrail = 10;  // s
  const allPoints = document.getElementById('all-points');
  // The certificate's uncovered area samples, coloured by reason: a verdict on the whole plan,
  // shown at its last frame only.
  const uncovered = new THREE.Group();
  partFrame.add(uncovered);
  if (D.uncovered) {
    const p = f32(D.uncovered), cls = bytes(D.uncovered_class);
    const col = new Float32Array(p.length);
    for (let i = 0; i < cls.length; ++i) {
      const c = new THREE.Color(D.classes[cls[i]].colour);
      col[3 * i] = c.r; col[3 * i + 1] = c.g; col[3 * i + 2] = c.b;
    }
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(p, 3));
    g.setAttribute('color', new THREE.BufferAttribute(col, 3));
    const pts = new THREE.Points(g, new THREE.PointsMaterial({ size: 0.003, vertexColors: true }));
    pts.name = 'uncovered';
    uncovered.add(pts);
  }

  // The laser fan in the scanner frame: a translucent red trapezoid, on while scanning.
  const fan = f32(D.fan);
  const fanGeometry = new THREE.BufferGeometry();
  fanGeometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array([
    ...fan.slice(0, 3), ...fan.slice(12, 15), ...fan.slice(9, 12)]), 3));
  const laser = new THREE.Mesh(fanGeometry, new THREE.MeshBasicMaterial({
    color: 0xff2020, transparent: true, opacity: 0.35, side: THREE.DoubleSide, depthWrite: false }));
  carriers[7].add(laser);
  const lineGeometry = new THREE.BufferGeometry();
  lineGeometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array([
    ...fan.slice(3, 6), ...fan.slice(6, 9), ...fan.slice(9, 12), ...fan.slice(12, 15),
    ...fan.slice(3, 6)]), 3));
  carriers[7].add(new THREE.Line(lineGeometry, new THREE.LineBasicMaterial({ color: 0xd01010 })));

  // Frames: time and the 9 carriers' poses (x y z, quaternion x y z w).
  const times = f32(D.frames.t), poses = f32(D.frames.poses), scanning = bytes(D.frames.scanning);
  const n = times.length;
  const tmp = { p: new THREE.Vector3(), q: new THREE.Quaternion(), s: new THREE.Vector3(1, 1, 1) };
  const slider = document.getElementById('time'), label = document.getElementById('label');
  const note = document.getElementById('note');
  slider.max = String(n - 1);
  let frame = 0;

  function upperBound(arr, x) {
    let lo = 0, hi = arr.length;
    while (lo < hi) { const mid = (lo + hi) >> 1; if (arr[mid] <= x) lo = mid + 1; else hi = mid; }
    return lo;
  }
  const frameAt = (t) => Math.max(0, upperBound(times, t) - 1);
  // Carrier k's pose at frame f into the matrix m.
  function pose(f, k, m) {
    const o = (f * 9 + k) * 7;
    tmp.p.set(poses[o], poses[o + 1], poses[o + 2]);
    tmp.q.set(poses[o + 3], poses[o + 4], poses[o + 5], poses[o + 6]);
    return m.compose(tmp.p, tmp.q, tmp.s);
  }

  // The closest approaches (once each): their two bodies glow red near that time, a red note says
  // how close, a red tick on the time slider marks each, and the button steps through them.
  const approaches = D.closest.filter((c, i) => D.closest.findIndex(
    (d) => d.a === c.a && d.b === c.b && d.t === c.t) === i);
  const kNear = Math.max(n > 1 ? 3 * (times[n - 1] - times[0]) / (n - 1) : 0, 2.5);  // s
  const mm = (m) => `${(m * 1000).toFixed(1)} mm`;
  function highlight(t) {
    for (const m of Object.values(meshes)) m.material.emissive.setHex(0);
    let text = '';
    for (const c of approaches) {
      if (Math.abs(t - c.t) > kNear) continue;
      for (const name of [c.a, c.b]) {
        if (!meshes[name]) continue;
        meshes[name].material.emissive.setHex(0xff0000);
        meshes[name].material.emissiveIntensity = 0.75;
      }
      text = `⚠ closest approach: ${c.a} – ${c.b}, ${mm(c.distance)} apart`;
    }
    note.textContent = text;
  }
  function addTicks() {
    const ticks = document.getElementById('ticks');
    if (!ticks || n < 2) return;
    for (const c of approaches) {
      const tick = document.createElement('i');
      const f = frameAt(c.t) / (n - 1);
      tick.style.left = `calc(${f} * (100% - 16px) + 8px)`;  // under the thumb's centre
      ticks.appendChild(tick);
    }
  }

  // The legend's density scale: its middle and top (colours saturate there), rounded.
  function scaleNumbers() {
    const top = D.density_top, mid = document.getElementById('scale-mid');
    if (!mid || !(top > 0)) return;
    const round = (x) => (x >= 10 ? String(Math.round(x)) : x.toPrecision(2));
    mid.textContent = round(top / 2);
    document.getElementById('scale-top').textContent = `≥ ${round(top)}`;
  }

  function setFrame(i) {
    frame = Math.max(0, Math.min(n - 1, Math.round(i)));
    for (let k = 0; k < 9; ++k) {
      pose(frame, k, carriers[k].matrix);
      carriers[k].matrixWorldNeedsUpdate = true;
    }
    const t = times[frame];
    const from = allPoints && allPoints.checked ? 0 : upperBound(cloudT, t - kTrail);
    const points = upperBound(cloudT, t) - from;
    cloudGeometry.setDrawRange(from, points);
    laser.visible = scanning[frame] === 1;
    coverage.update(t, frame === n - 1);
    uncovered.visible = frame === n - 1;
    slider.value = String(frame);
    label.textContent = `t = ${t.toFixed(1)} s of ${times[n - 1].toFixed(1)} s` +
      (scanning[frame] ? ' · scanning' : ' · moving') +
      ` · ${points.toLocaleString()} points shown`;
    highlight(t);
    render();
  }

  // The view: from the front-right and above, just far enough that every body fits, wherever it
  // is at every 50th frame and the last, with a margin, for the window's aspect ratio. Refitted on
  // resize until the user turns, zooms or pans.
  const kViewFrom = new THREE.Vector3(1.2, -1.9, 1.0).normalize();
  const kMargin = 0.06;  // of the half-height and half-width
  function sweptPoints() {  // up to ~300 vertices a body, at each of those frames
    const out = [], m = new THREE.Matrix4(), frames = [n - 1];
    for (let f = 0; f < n - 1; f += 50) frames.push(f);
    D.bodies.forEach((b, j) => {
      const v = bodyMeshes[j].geometry.getAttribute('position');
      const step = Math.max(1, Math.floor(v.count / 300));
      for (const f of b.frame < 0 ? [-1] : frames) {
        if (f < 0) m.identity(); else pose(f, b.frame, m);
        for (let i = 0; i < v.count; i += step) {
          out.push(new THREE.Vector3().fromBufferAttribute(v, i).applyMatrix4(m));
        }
      }
    });
    return out;
  }
  const swept = sweptPoints();
  // The camera at target + d · kViewFrom with the smallest d that shows every swept point, the
  // target moved (three passes) to centre them in the picture, the picture slid right off the
  // legend as far as the margin allows. x, y, z: the points in the camera's axes (right, up,
  // towards the camera) about the swept box's centre; moving the target moves only x and y.
  let shift = 0;  // px
  function fitView() {
    const right = new THREE.Vector3().crossVectors(camera.up, kViewFrom).normalize();
    const up = new THREE.Vector3().crossVectors(kViewFrom, right);
    const centre = new THREE.Box3().setFromPoints(swept).getCenter(new THREE.Vector3());
    const m = swept.length, r = new THREE.Vector3();
    const x = new Float64Array(m), y = new Float64Array(m), z = new Float64Array(m);
    swept.forEach((p, i) => {
      r.subVectors(p, centre);
      x[i] = r.dot(right); y[i] = r.dot(up); z[i] = r.dot(kViewFrom);
    });
    const tan = Math.tan(THREE.MathUtils.degToRad(camera.fov) / 2);
    const ty = tan * (1 - kMargin), tx = ty * camera.aspect;
    const distance = (ox, oy) => {
      let d = 0;
      for (let i = 0; i < m; ++i) {
        d = Math.max(d, z[i] + Math.abs(x[i] - ox) / tx, z[i] + Math.abs(y[i] - oy) / ty);
      }
      return d;
    };
    const extent = (ox, oy, d) => {  // on the picture, x and y ranges in tan units
      const e = [Infinity, -Infinity, Infinity, -Infinity];
      for (let i = 0; i < m; ++i) {
        const depth = Math.max(d - z[i], 1e-9);
        const sx = (x[i] - ox) / depth, sy = (y[i] - oy) / depth;
        e[0] = Math.min(e[0], sx); e[1] = Math.max(e[1], sx);
        e[2] = Math.min(e[2], sy); e[3] = Math.max(e[3], sy);
      }
      return e;
    };
    let ox = 0, oy = 0;
    for (let pass = 0; pass < 3; ++pass) {
      const d = distance(ox, oy), e = extent(ox, oy, d);
      ox += d * (e[0] + e[1]) / 2; oy += d * (e[2] + e[3]) / 2;
    }
    const d = distance(ox, oy), e = extent(ox, oy, d);
    shift = legendShift(Math.max(-e[0], e[1]) / (tan * camera.aspect));
    controls.target.copy(centre).addScaledVector(right, ox).addScaledVector(up, oy);
    camera.position.copy(controls.target).addScaledVector(kViewFrom, d);
    camera.far = Math.max(50, 4 * d);
    controls.update();
  }
  // px to slide the picture right so that the swept bodies, halfWidth of the view's half-width
  // either side of its middle, clear the legend, within the margin.
  function legendShift(halfWidth) {
    const box = document.getElementById('legend'), w = view.clientWidth;
    if (!box) return 0;
    const room = (1 - kMargin - halfWidth) * w / 2;
    const wanted = box.offsetLeft + box.offsetWidth + 8 - (1 - halfWidth) * w / 2;
    return Math.max(0, Math.min(room, wanted));
  }

  const controls = new THREE.OrbitControls(camera, renderer.domElement);
  let moved = false;  // by the user
  controls.addEventListener('start', () => { moved = true; });
  controls.addEventListener('change', () => render());
  function resize() {
    const w = view.clientWidth, h = Math.max(view.clientHeight, 1);
    renderer.setSize(w, h);
    camera.aspect = w / h;
    if (!moved) fitView();
    camera.setViewOffset(w, h, -shift, 0, w, h);  // updates the projection
    render();
  }
  function render() { renderer.render(scene, camera); }

  // Play / pause: `speed` seconds of plan per second of replay.
  let playing = false, last = 0, clock = 0;
  const play = document.getElementById('play'), speed = document.getElementById('speed');
  const stop = () => { playing = false; play.textContent = '▶ Play'; };
  function tick(now) {
    if (!playing) return;
    if (last) clock += (now - last) / 1000 * Number(speed.value);
    last = now;
    const i = upperBound(times, times[0] + clock) - 1;
    setFrame(i);
    if (i >= n - 1) { stop(); return; }
    requestAnimationFrame(tick);
  }
  play.addEventListener('click', () => {
    playing = !playing;
    play.textContent = playing ? '❚❚ Pause' : '▶ Play';
    if (playing) {
      if (frame >= n - 1) frame = 0;
      clock = times[frame] - times[0];
      last = 0;
      requestAnimationFrame(tick);
    }
  });
  slider.addEventListener('input', () => { stop(); setFrame(Number(slider.value)); });
  let nextApproach = 0;
  document.getElementById('closest').addEventListener('click', () => {
    if (!approaches.length) return;
    stop();
    setFrame(frameAt(approaches[nextApproach].t));
    nextApproach = (nextApproach + 1) % approaches.length;
  });
  if (allPoints) allPoints.addEventListener('change', () => setFrame(frame));
  addTicks();
  scaleNumbers();
  window.addEventListener('resize', resize);
  resize();
  const start = Number((location.hash.match(/frame=(\d+)/) || [])[1] || 0);
  setFrame(start);
  window.scanplanReplay = {
    frames: n, setFrame, get frame() { return frame; }, coloured: coverage.coloured, ready: true,
  };
})();
