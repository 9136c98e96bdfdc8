/* affordgrasp grasp viewer: one self-contained page, three.js (global THREE) inlined before it.
 *
 * The page embeds a JSON document (script#affordgrasp-data) with the objects, the hands' link
 * meshes, and one entry per grasp (link poses, contacts, use point, wrist axis, camera).
 * When the first frame is drawn, <html data-status="ready" data-drawn="N"> tells how many
 * pixels differ from the background (0 would mean an empty canvas); "no-webgl" when the
 * browser has no WebGL (the PNG of each grasp is shown instead).
 */
(function () {
  "use strict";

  const root = document.documentElement;
  const setStatus = (s) => { root.dataset.status = s; };
  const data = JSON.parse(document.getElementById("affordgrasp-data").textContent);

  const COLORS = {
    background: 0xffffff, object: 0xbdbdb8, palm: 0x3d5c9e, finger: 0x6690db,
    contact: 0xff8c00, cone: 0xe0a030, use: 0xd62728, wrist: 0x2ca02c, com: 0x111111,
  };

  function decode(b64, Type) {
    const bin = atob(b64);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    return new Type(bytes.buffer);
  }

  function geometryOf(m) {
    const g = new THREE.BufferGeometry();
    g.setAttribute("position", new THREE.BufferAttribute(decode(m.positions, Float32Array), 3));
    g.setAttribute("normal", new THREE.BufferAttribute(decode(m.normals, Int8Array), 3, true));
    const Index = m.index_type === "uint16" ? Uint16Array : Uint32Array;
    g.setIndex(new THREE.BufferAttribute(decode(m.index, Index), 1));
    g.computeBoundingSphere();
    return g;
  }

  // ------------------------------------------------------------------ list of grasps
  const list = document.getElementById("grasp-list");
  const info = document.getElementById("grasp-info");
  const caption = document.getElementById("view-caption");
  const cards = [];
  data.grasps.forEach((g, i) => {
    if (g.group && (i === 0 || data.grasps[i - 1].group !== g.group)) {
      const h = document.createElement("h3");
      h.textContent = g.group;
      list.appendChild(h);
    }
    const card = document.createElement("button");
    card.className = "card";
    card.type = "button";
    if (g.thumbnail) {
      const img = document.createElement("img");
      img.src = g.thumbnail;
      img.alt = g.title;
      card.appendChild(img);
    }
    const t = document.createElement("span");
    t.textContent = g.title;
    card.appendChild(t);
    card.addEventListener("click", () => select(i));
    list.appendChild(card);
    cards.push(card);
  });

  function showInfo(g) {
    info.replaceChildren();
    const table = document.createElement("table");
    for (const [k, v] of g.facts) {
      const tr = document.createElement("tr");
      const th = document.createElement("th");
      const td = document.createElement("td");
      th.textContent = k;
      td.textContent = v;
      tr.append(th, td);
      table.appendChild(tr);
    }
    info.appendChild(table);
    caption.textContent = g.title;
  }

  // ------------------------------------------------------------------ WebGL
  const canvas = document.getElementById("view");
  const probe = document.createElement("canvas");
  const probeContext = probe.getContext("webgl2") || probe.getContext("webgl");
  const hasWebGL = !!probeContext;
  if (probeContext) {
    const lose = probeContext.getExtension("WEBGL_lose_context");
    if (lose) lose.loseContext();
  }
  let current = -1;
  if (!hasWebGL) {
    document.getElementById("view-box").classList.add("no-webgl");
    select(0);
    setStatus("no-webgl");
    return;
  }

  const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setClearColor(COLORS.background, 1);
  const scene = new THREE.Scene();
  const camera = new THREE.PerspectiveCamera(30, 1, 0.001, 100);
  scene.add(camera);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x8a8a8a, 1.6));
  const key = new THREE.DirectionalLight(0xffffff, 1.8);
  key.position.set(-0.5, 0.6, 1.0);
  camera.add(key); // the light follows the camera, as in the PNG renders
  const controls = new THREE.OrbitControls(camera, canvas);
  controls.enableDamping = false;
  controls.addEventListener("change", draw);

  const objectGeometries = data.objects.map((o) => geometryOf(o.mesh));
  const handGeometries = {};
  for (const [name, hand] of Object.entries(data.hands)) {
    handGeometries[name] = hand.links.map((l) => (l ? { geometry: geometryOf(l.mesh), palm: l.palm } : null));
  }
  const materials = {
    object: new THREE.MeshLambertMaterial({ color: COLORS.object }),
    palm: new THREE.MeshLambertMaterial({ color: COLORS.palm }),
    finger: new THREE.MeshLambertMaterial({ color: COLORS.finger }),
    contact: new THREE.MeshBasicMaterial({ color: COLORS.contact, depthTest: false }),
    use: new THREE.MeshBasicMaterial({ color: COLORS.use, depthTest: false }),
    com: new THREE.MeshBasicMaterial({ color: COLORS.com, depthTest: false }),
    cone: new THREE.MeshBasicMaterial({ color: COLORS.cone, wireframe: true, transparent: true, opacity: 0.7, depthTest: false }),
    wrist: new THREE.LineDashedMaterial({ color: COLORS.wrist, dashSize: 0.01, gapSize: 0.005 }),
  };

  const layers = {};
  const toggles = {};
  document.querySelectorAll("#toggles input[type=checkbox]").forEach((box) => {
    toggles[box.name] = box;
    box.addEventListener("change", applyToggles);
  });

  function applyToggles() {
    for (const [name, group] of Object.entries(layers)) {
      if (toggles[name]) group.visible = toggles[name].checked;
    }
    const xray = !!(toggles.xray && toggles.xray.checked);
    for (const m of [materials.palm, materials.finger]) {
      // Opaque unless see-through: transparent meshes are drawn last, over the markers.
      m.transparent = xray;
      m.opacity = xray ? 0.35 : 1.0;
      m.depthWrite = !xray;
      m.needsUpdate = true;
    }
    draw();
  }

  function arrow(origin, dir, length, color) {
    const o = new THREE.Vector3(...origin);
    const d = new THREE.Vector3(...dir).normalize();
    const a = new THREE.ArrowHelper(d, o, length, color, 0.25 * length, 0.12 * length);
    a.line.material.depthTest = false;
    a.cone.material.depthTest = false;
    a.renderOrder = 10;
    return a;
  }

  function ball(p, r, material) {
    const m = new THREE.Mesh(new THREE.SphereGeometry(r, 16, 12), material);
    m.position.set(...p);
    m.renderOrder = 11;
    return m;
  }

  function finite(v) {
    return Array.isArray(v) && v.every((x) => typeof x === "number" && isFinite(x));
  }

  function clearScene() {
    for (const group of Object.values(layers)) {
      scene.remove(group);
      group.traverse((o) => {
        if (o.geometry && !o.userData.shared) o.geometry.dispose();
      });
    }
    for (const k of Object.keys(layers)) delete layers[k];
  }

  function build(g) {
    clearScene();
    const size = g.size;
    const mk = (name) => {
      const group = new THREE.Group();
      layers[name] = group;
      scene.add(group);
      return group;
    };
    const obj = new THREE.Mesh(objectGeometries[g.object], materials.object);
    obj.userData.shared = true;
    mk("object").add(obj);

    const hand = mk("hand");
    handGeometries[g.hand].forEach((l, i) => {
      if (!l) return;
      const m = new THREE.Mesh(l.geometry, l.palm ? materials.palm : materials.finger);
      m.userData.shared = true;
      m.matrixAutoUpdate = false;
      m.matrix.set(...g.link_poses[i]); // row-major 4x4, link -> object
      hand.add(m);
    });

    const contacts = mk("contacts");
    const cones = mk("cones");
    const r = 0.009 * size;
    g.contacts.points.forEach((p, i) => {
      const n = g.contacts.normals[i];
      contacts.add(ball(p, r, materials.contact));
      contacts.add(arrow(p, n, 0.08 * size, COLORS.contact));
      const mu = g.contacts.mu[i];
      const h = 0.07 * size;
      const cone = new THREE.Mesh(new THREE.ConeGeometry(h * mu, h, 16, 1, true), materials.cone);
      // ConeGeometry points its apex to +y: flip it so the apex sits on the contact.
      const axis = new THREE.Vector3(...n).normalize();
      cone.quaternion.setFromUnitVectors(new THREE.Vector3(0, -1, 0), axis);
      cone.position.set(...p).addScaledVector(axis, 0.5 * h);
      cone.renderOrder = 9;
      cones.add(cone);
    });

    const use = mk("use");
    if (finite(g.use_point)) {
      use.add(ball(g.use_point, 1.3 * r, materials.use));
      if (finite(g.use_normal)) use.add(arrow(g.use_point, g.use_normal, 0.1 * size, COLORS.use));
    }

    const wrist = mk("wrist");
    if (finite(g.wrist_point) && finite(g.wrist_axis)) {
      const p = new THREE.Vector3(...g.wrist_point);
      const a = new THREE.Vector3(...g.wrist_axis).normalize();
      const geo = new THREE.BufferGeometry().setFromPoints([
        p.clone().addScaledVector(a, -0.3 * size),
        p.clone().addScaledVector(a, 0.4 * size),
      ]);
      materials.wrist.dashSize = 0.03 * size;
      materials.wrist.gapSize = 0.015 * size;
      const line = new THREE.Line(geo, materials.wrist);
      line.computeLineDistances();
      wrist.add(line);
    }

    const com = mk("com");
    if (finite(g.com)) com.add(ball(g.com, 0.8 * r, materials.com));
    applyToggles();
  }

  function resetCamera(g) {
    const c = g.camera;
    camera.fov = c.fov;
    camera.near = Math.max(1e-4, 0.01 * g.size);
    camera.far = 100 * g.size + 10;
    camera.up.set(...c.up);
    camera.position.set(...c.eye);
    controls.target.set(...c.target);
    camera.lookAt(controls.target);
    camera.updateProjectionMatrix();
    controls.update();
    draw();
  }

  function resize() {
    const box = canvas.parentElement.getBoundingClientRect();
    const w = Math.max(1, Math.floor(box.width));
    const h = Math.max(1, Math.floor(box.height));
    renderer.setSize(w, h, false);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    draw();
  }

  function draw() {
    renderer.render(scene, camera);
  }

  let reported = false;
  function reportFirstFrame() {
    // Once, after the first grasp is drawn: how many pixels are not background.
    if (reported) return;
    reported = true;
    draw();
    root.dataset.drawn = String(countDrawnPixels());
    setStatus("ready");
  }

  function countDrawnPixels() {
    const gl = renderer.getContext();
    const w = gl.drawingBufferWidth;
    const h = gl.drawingBufferHeight;
    const px = new Uint8Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    let n = 0;
    for (let i = 0; i < px.length; i += 4) {
      if (px[i] < 250 || px[i + 1] < 250 || px[i + 2] < 250) n++;
    }
    return n;
  }

  function select(i) {
    if (i < 0 || i >= data.grasps.length) return;
    current = i;
    cards.forEach((c, j) => c.classList.toggle("selected", j === i));
    cards[i].scrollIntoView({ block: "nearest" });
    const g = data.grasps[i];
    showInfo(g);
    if (!hasWebGL) {
      document.getElementById("fallback").src = g.thumbnail || "";
      return;
    }
    build(g);
    resetCamera(g);
    reportFirstFrame();
  }
  // For scripts and tests driving the page.
  window.affordgraspViewer = {
    select,
    count: () => data.grasps.length,
    drawnPixels: () => { draw(); return countDrawnPixels(); },
    setLayer: (name, on) => { toggles[name].checked = !!on; applyToggles(); },
  };

  document.getElementById("reset-view").addEventListener("click", () => resetCamera(data.grasps[current]));
  document.addEventListener("keydown", (e) => {
    if (e.target && e.target.tagName === "INPUT") return;
    if (e.key === "ArrowRight" || e.key === "ArrowDown" || e.key === "j") select(current + 1);
    if (e.key === "ArrowLeft" || e.key === "ArrowUp" || e.key === "k") select(current - 1);
    if (e.key === "r") resetCamera(data.grasps[current]);
  });
  if (window.ResizeObserver) new ResizeObserver(resize).observe(canvas.parentElement);
  window.addEventListener("resize", resize);
  resize();
  select(0);
})();
