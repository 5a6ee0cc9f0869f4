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
  const meshes = {};
  for (const b of D.bodies) {
    const g = new THREE.BufferGeometry();
    const v = f32(b.vertices), t = u32(b.triangles);
    if (b.colours) {  // per triangle: unshared vertices carry the triangle's colour
      const c = bytes(b.colours);
      const pos = new Float32Array(t.length * 3), col = new Float32Array(t.length * 3);
      for (let i = 0; i < t.length; ++i) {
        for (let a = 0; a < 3; ++a) {
          pos[3 * i + a] = v[3 * t[i] + a];
          col[3 * i + a] = c[3 * Math.floor(i / 3) + a] / 255;
        }
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
    (b.frame >= 0 ? carriers[b.frame] : scene).add(mesh);
  }

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
    partFrame.add(pts);
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
  function highlight(t) {
    for (const m of Object.values(meshes)) m.material.emissive && m.material.emissive.setHex(0);
    const span = n > 1 ? 2 * (times[n - 1] - times[0]) / n : 1;
    let text = '';
    for (const c of D.closest) {
      if (Math.abs(t - c.t) > Math.max(span, 0.5)) continue;
      for (const name of [c.a, c.b]) if (meshes[name]) meshes[name].material.emissive.setHex(0xcc0000);
      text = `closest here: ${c.a} – ${c.b} ${(c.distance * 1000).toFixed(1)} mm at t = ${c.t.toFixed(1)} s`;
    }
    note.textContent = text;
  }
  function setFrame(i) {
    frame = Math.max(0, Math.min(n - 1, Math.round(i)));
    for (let k = 0; k < 9; ++k) {
      const o = (frame * 9 + k) * 7;
      tmp.p.set(poses[o], poses[o + 1], poses[o + 2]);
      tmp.q.set(poses[o + 3], poses[o + 4], poses[o + 5], poses[o + 6]);
      carriers[k].matrix.compose(tmp.p, tmp.q, tmp.s);
      carriers[k].matrixWorldNeedsUpdate = true;
    }
    const t = times[frame];
    cloudGeometry.setDrawRange(0, upperBound(cloudT, t));
    laser.visible = scanning[frame] === 1;
    slider.value = String(frame);
    label.textContent = `t = ${t.toFixed(1)} s of ${times[n - 1].toFixed(1)} s` +
      (scanning[frame] ? ' · scanning' : ' · moving') +
      ` · ${upperBound(cloudT, t).toLocaleString()} points shown`;
    highlight(t);
    render();
  }

  const controls = new THREE.OrbitControls(camera, renderer.domElement);
  controls.target.fromArray(D.look_at);
  camera.position.fromArray(D.eye);
  controls.update();
  controls.addEventListener('change', () => render());
  function resize() {
    const w = view.clientWidth, h = view.clientHeight;
    renderer.setSize(w, h);
    camera.aspect = w / Math.max(h, 1);
    camera.updateProjectionMatrix();
    render();
  }
  function render() { renderer.render(scene, camera); }

  // Play / pause: `speed` seconds of plan per second of replay.
  let playing = false, last = 0, clock = 0;
  const play = document.getElementById('play'), speed = document.getElementById('speed');
  function tick(now) {
    if (!playing) return;
    if (last) clock += (now - last) / 1000 * Number(speed.value);
    last = now;
    const i = upperBound(times, times[0] + clock) - 1;
    setFrame(i);
    if (i >= n - 1) { playing = false; play.textContent = '▶ Play'; return; }
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
  slider.addEventListener('input', () => { playing = false; play.textContent = '▶ Play'; setFrame(Number(slider.value)); });
  document.getElementById('closest').addEventListener('click', () => {
    if (D.closest.length) setFrame(upperBound(times, D.closest[0].t) - 1);
  });
  window.addEventListener('resize', resize);
  resize();
  const start = Number((location.hash.match(/frame=(\d+)/) || [])[1] || 0);
  setFrame(start);
  window.scanplanReplay = { frames: n, setFrame, get frame() { return frame; }, ready: true };
})();
