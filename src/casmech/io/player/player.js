// casmech HTML player on three.js (inlined before this script as the global THREE), no network.
// Data (JSON in #casmech-data, html_player.py): parts (body-frame triangle surfaces), links, and
// per frame the CM position r and unit Euler parameters p of every body (x = r + A(p) x_bar),
// the mechanism's centre and radius; the ground plane, contact planes, joint frames, force
// vectors (value per frame, SI units; origin per frame or a point fixed in a body), trails
// (overlays.py).
(function () {
  'use strict';
  var status = document.getElementById('status');
  function report(text) { status.textContent = text; }
  window.addEventListener('error', function (event) {
    report('error: ' + (event.message || event.error));
  });

  var T = window.THREE;
  var D = JSON.parse(document.getElementById('casmech-data').textContent);
  var host = document.getElementById('view');
  var slider = document.getElementById('slider');
  var playButton = document.getElementById('play');
  var timeLabel = document.getElementById('time');
  var speedSelect = document.getElementById('speed');
  var panel = document.getElementById('panel');
  var nb = D.bodies.length, nFrames = D.times.length;
  var PALETTE = [0x4285f4, 0xdb4437, 0xf4b400, 0x0f9d58, 0xab47bc, 0x00acc1, 0xff7043,
    0x9e9d24, 0x5c6bc0, 0xf06292];
  var MARKER = 0x50555e, GROUND = 0xdfe3e8, BACKGROUND = 0xeef1f5;
  var VECTORS = {  // arrow kind -> [toggle, colour, double head (a torque)]
    force: ['forces', 0xe65100, false], torque: ['torques', 0x8e24aa, true],
    motor_torque: ['motors', 0x2e7d32, true], motor_force: ['motors', 0x2e7d32, false],
    normal: ['contacts', 0xd81b60, false], friction: ['contacts', 0x6d4c41, false]
  };
  var SHOWN = { bodies: false, joints: false, frames: false, shapes: false, forces: false,
    torques: false,
    motors: true, contacts: true, trails: D.trails.some(function (t) { return t.chosen; }),
    grid: true, shadows: true };

  // ---------------------------------------------------------------------------- the view
  var renderer;
  try {
    renderer = new T.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  } catch (error) {
    host.innerHTML = '<p id="nowebgl">This browser cannot draw WebGL, which the player needs.</p>';
    report('error: no WebGL (' + error.message + ')');
    return;
  }
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.outputColorSpace = T.SRGBColorSpace;
  renderer.shadowMap.enabled = true;
  renderer.shadowMap.type = T.PCFShadowMap;
  host.appendChild(renderer.domElement);
  var labels = new T.CSS2DRenderer();
  labels.domElement.style.position = 'absolute';
  labels.domElement.style.top = '0';
  labels.domElement.style.pointerEvents = 'none';
  host.appendChild(labels.domElement);

  function vector(a, k) { return new T.Vector3(a[3 * k], a[3 * k + 1], a[3 * k + 2]); }
  var up = vector(D.up, 0).normalize();
  var scene = new T.Scene();
  scene.background = new T.Color(BACKGROUND);
  var typical = D.radii.slice().sort(function (a, b) { return a - b; })[nFrames >> 1];
  // what a view shows: the mechanism, and around a small one travelling far some of its path
  function around(radius) { return Math.max(radius, Math.min(0.5 * D.radius, 4 * radius)); }
  var reach = around(typical);
  var camera = new T.PerspectiveCamera(40, 1, typical / 100, typical * 100);
  camera.up.copy(up);
  var controls = new T.OrbitControls(camera, renderer.domElement);
  controls.addEventListener('change', function () { render(); });

  scene.add(new T.HemisphereLight(0xffffff, 0x8d8d8d, 1.3));
  var sun = new T.DirectionalLight(0xffffff, 2.2);
  sun.castShadow = true;
  sun.shadow.mapSize.set(2048, 2048);
  sun.shadow.bias = -0.0005;
  sun.shadow.normalBias = 0.02 * typical / 50;
  scene.add(sun, sun.target);
  var fill = new T.DirectionalLight(0xffffff, 0.9);  // from the viewer: no face is left dark
  scene.add(fill, fill.target);
  var across = new T.Vector3(1, 0, 0);
  if (Math.abs(across.dot(up)) > 0.9) across.set(0, 1, 0);
  across.sub(up.clone().multiplyScalar(across.dot(up))).normalize();
  var across2 = new T.Vector3().crossVectors(up, across);

  // ------------------------------------------------------------------------ the bodies
  function material(colour, extra) {
    return new T.MeshStandardMaterial(Object.assign({ color: colour, roughness: 0.55,
      metalness: 0.05, side: T.DoubleSide }, extra || {}));
  }
  var frames = [];  // a Group per body; index nb: the scene (ground)
  for (var b = 0; b < nb; b++) {
    var group = new T.Group();
    group.matrixAutoUpdate = true;
    scene.add(group);
    frames.push(group);
  }
  frames.push(scene);
  function frameOf(body) { return frames[body < 0 ? nb : body]; }
  function colourOf(body) { return PALETTE[((body % 10) + 10) % 10]; }

  var materials = {};
  D.parts.forEach(function (part) {
    var geometry = new T.BufferGeometry();
    geometry.setAttribute('position', new T.Float32BufferAttribute(part.points, 3));
    geometry.setIndex(part.triangles);
    geometry = T.toCreasedNormals(geometry, Math.PI / 6);
    var colour = part.joint >= 0 || part.body < 0 ? MARKER : colourOf(part.body);
    materials[colour] = materials[colour] || material(colour);
    var mesh = new T.Mesh(geometry, materials[colour]);
    mesh.castShadow = true;
    mesh.receiveShadow = true;
    frameOf(part.body).add(mesh);
  });

  var ghost = material(0x78909c, { transparent: true, opacity: 0.35, depthWrite: false });
  var contactShapes = D.shapes.map(function (shape) {
    var geometry = new T.BufferGeometry();
    geometry.setAttribute('position', new T.Float32BufferAttribute(shape.points, 3));
    geometry.setIndex(shape.triangles);
    var mesh = new T.Mesh(T.toCreasedNormals(geometry, Math.PI / 6), ghost);
    frameOf(shape.body).add(mesh);
    return mesh;
  });

  var linkPositions = new Float32Array(6 * D.links.length);
  var links = new T.LineSegments(new T.BufferGeometry(), new T.LineBasicMaterial({ color: 0x333333 }));
  links.geometry.setAttribute('position', new T.BufferAttribute(linkPositions, 3));
  links.frustumCulled = false;
  scene.add(links);

  // ------------------------------------------------------------- ground, grid, planes
  function niceStep(x) {  // 1, 2 or 5 times a power of ten, at most x
    var power = Math.pow(10, Math.floor(Math.log10(x)));
    return x / power >= 5 ? 5 * power : x / power >= 2 ? 2 * power : power;
  }
  var groundPoint = vector(D.ground.point, 0), groundUp = vector(D.ground.normal, 0).normalize();
  var middle = vector(D.center, 0);
  middle.sub(groundUp.clone().multiplyScalar(middle.clone().sub(groundPoint).dot(groundUp)));
  var size = 2 * (1.5 * D.radius + 2 * typical);
  var step = niceStep(size / 40);
  var cells = 2 * Math.ceil(size / step / 2);
  size = cells * step;
  var snapped = middle.clone();  // grid lines through the global origin's projection
  var toGround = new T.Quaternion().setFromUnitVectors(new T.Vector3(0, 0, 1), groundUp);
  var floor = new T.Mesh(new T.PlaneGeometry(size, size),
    new T.MeshStandardMaterial({ color: GROUND, roughness: 1, metalness: 0 }));
  floor.quaternion.copy(toGround);
  floor.position.copy(snapped).addScaledVector(groundUp, -1e-4 * typical);
  floor.receiveShadow = true;
  var grid = new T.GridHelper(size, cells, 0x9aa3ad, 0xbfc6ce);
  grid.quaternion.setFromUnitVectors(new T.Vector3(0, 1, 0), groundUp);
  grid.position.copy(snapped).addScaledVector(groundUp, 1e-3 * typical);
  scene.add(floor, grid);

  D.planes.forEach(function (plane) {
    var quad = new T.Mesh(new T.PlaneGeometry(1.5 * typical, 1.5 * typical),
      material(0x90a4ae, { transparent: true, opacity: 0.45 }));
    quad.quaternion.setFromUnitVectors(new T.Vector3(0, 0, 1), vector(plane.normal, 0).normalize());
    quad.position.copy(vector(plane.point, 0));
    quad.receiveShadow = true;
    if (plane.body < 0 && Math.abs(vector(plane.normal, 0).normalize().dot(groundUp)) > 0.999 &&
        Math.abs(vector(plane.point, 0).sub(groundPoint).dot(groundUp)) < 1e-9 * typical) return;
    frameOf(plane.body).add(quad);
  });

  // ---------------------------------------------------------------------- arrows
  var Y = new T.Vector3(0, 1, 0);
  var shaftGeometry = new T.CylinderGeometry(1, 1, 1, 12);
  shaftGeometry.translate(0, 0.5, 0);
  var headGeometry = new T.ConeGeometry(1, 1, 16);
  headGeometry.translate(0, -0.5, 0);  // tip at the origin
  var thick = 0.01 * reach;
  function arrow(colour, heads, onTop) {  // onTop: drawn over the bodies (forces inside them)
    var group = new T.Group();
    var paint = new T.MeshStandardMaterial({ color: colour, roughness: 0.4, depthTest: !onTop,
      emissive: new T.Color(colour).multiplyScalar(0.45) });
    var shaft = new T.Mesh(shaftGeometry, paint);
    group.add(shaft);
    var tips = [];
    for (var h = 0; h < heads; h++) {
      var tip = new T.Mesh(headGeometry, paint);
      group.add(tip);
      tips.push(tip);
    }
    group.userData = { shaft: shaft, tips: tips };
    if (onTop) group.traverse(function (mesh) { mesh.renderOrder = 10; });
    return group;
  }
  function pointArrow(group, origin, direction, length) {  // length in metres
    if (!(length > 1e-12 * typical)) { group.visible = false; return; }
    group.visible = true;
    group.position.copy(origin);
    group.quaternion.setFromUnitVectors(Y, direction);
    var head = Math.min(4 * thick, 0.4 * length), width = Math.min(thick, 0.15 * length);
    group.userData.shaft.scale.set(width, length - head * (group.userData.tips.length > 1 ? 1.6 : 1), width);
    group.userData.tips.forEach(function (tip, n) {
      tip.scale.set(2.2 * width, head, 2.2 * width);
      tip.position.set(0, length - 0.6 * head * n, 0);
    });
  }
  var magnitudes = {};  // unit -> the nonzero magnitudes of its vectors over every frame
  var vectors = D.arrows.map(function (a) {
    var kind = VECTORS[a.kind], list = magnitudes[a.unit] = magnitudes[a.unit] || [];
    for (var k = 0; k < nFrames; k++) {
      var length = vector(a.vector, k).length();
      if (length > 0) list.push(length);
    }
    var group = arrow(kind[1], kind[2] ? 2 : 1, true);
    scene.add(group);
    return { data: a, group: group, toggle: kind[0] };
  });
  var usual = {};  // unit -> the 90th percentile of its magnitudes (a contact's impacts aside)
  Object.keys(magnitudes).forEach(function (unit) {
    var list = magnitudes[unit].sort(function (a, b) { return a - b; });
    usual[unit] = list.length ? list[Math.floor(0.9 * (list.length - 1))] : 0;
  });
  var scaleSlider = document.getElementById('scale');
  function metresPer(unit) {  // a usual vector of a unit spans half of what the view shows
    return usual[unit] > 0 ? 0.5 * reach / usual[unit] * Math.pow(10, Number(scaleSlider.value)) : 0;
  }
  function describeScales() {
    var text = Object.keys(usual).filter(function (u) { return usual[u] > 0; })
      .map(function (u) { return '1 m = ' + (1 / metresPer(u)).toPrecision(3) + ' ' + u; });
    document.getElementById('scales').textContent = text.join(' \u00b7 ');
  }

  // ---------------------------------------------------------------- joint frames, trails
  var triads = D.triads.map(function (triad) {
    var group = new T.Group(), L = 0.12 * reach;
    [0xd32f2f, 0x388e3c, 0x1976d2].forEach(function (colour, axis) {
      var a = arrow(colour, 1), save = thick;
      thick = 0.4 * save;
      pointArrow(a, new T.Vector3(), new T.Vector3(triad.axes[axis], triad.axes[3 + axis],
        triad.axes[6 + axis]).normalize(), L);
      thick = save;
      group.add(a);
    });
    group.position.copy(vector(triad.origin, 0));
    frameOf(triad.body).add(group);
    return group;
  });
  var dot = new T.SphereGeometry(0.012 * reach, 12, 8);
  var trails = D.trails.map(function (trail, n) {
    var tint = new T.Color(colourOf(trail.body >= 0 ? trail.body : n)).multiplyScalar(0.7);
    var line = new T.Line(new T.BufferGeometry(), new T.LineBasicMaterial({ color: tint }));
    line.geometry.setAttribute('position', new T.Float32BufferAttribute(trail.points, 3));
    line.frustumCulled = false;
    line.add(new T.Mesh(dot, new T.MeshBasicMaterial({ color: tint })));  // the point now
    scene.add(line);
    return line;
  });

  // ---------------------------------------------------------------------- labels
  function label(text, kind) {
    var div = document.createElement('div');
    div.className = 'label ' + kind;
    div.textContent = text;
    return new T.CSS2DObject(div);
  }
  var bodyLabels = D.bodies.map(function (name, b) {
    var tag = label(name, 'body');
    frames[b].add(tag);
    return tag;
  });
  var jointLabels = D.triads.map(function (triad) {
    var tag = label(triad.name, 'joint');
    tag.position.copy(vector(triad.origin, 0));
    frameOf(triad.body).add(tag);
    return tag;
  });

  // ---------------------------------------------------------------------- the camera
  var follow = D.follow;  // 'free', 'mechanism' or 'body:' and a body's name
  var cameraSelect = document.getElementById('camera');
  ['free', 'mechanism'].concat(D.bodies.map(function (name) { return 'body:' + name; }))
    .forEach(function (value, n) {
      var option = document.createElement('option');
      option.value = value;
      option.textContent = n === 0 ? 'free' : n === 1 ? 'follow the mechanism' :
        'follow ' + value.slice(5);
      cameraSelect.appendChild(option);
    });
  cameraSelect.value = follow;
  function followed(k) {  // the point the camera follows at frame k, or null
    if (follow === 'mechanism') return vector(D.centres, k);
    var b = follow.slice(0, 5) === 'body:' ? D.bodies.indexOf(follow.slice(5)) : -1;
    return b >= 0 ? vector(D.r, k * nb + b) : null;
  }
  function resize() {
    var width = Math.max(1, host.clientWidth), height = Math.max(1, host.clientHeight);
    renderer.setSize(width, height);
    labels.setSize(width, height);
    camera.aspect = width / height;
    camera.updateProjectionMatrix();
  }
  function fit(k, direction) {  // the whole mechanism at frame k in view, seen from direction
    var centre = vector(D.centres, k), radius = around(D.radii[k]);
    var half = Math.PI / 360 * camera.fov;
    var narrow = Math.min(half, Math.atan(Math.tan(half) * camera.aspect));
    var distance = 1.08 * radius / Math.sin(narrow);
    var from = direction || camera.position.clone().sub(controls.target).normalize();
    controls.target.copy(centre);
    camera.position.copy(centre).addScaledVector(from, distance);
    clip(distance);
  }
  function clip(distance) {
    camera.near = Math.max(1e-4 * distance, distance - 4 * D.radius, distance / 200);
    camera.far = distance + 8 * D.radius + 4 * typical;
    camera.updateProjectionMatrix();
    controls.update();
  }

  // ---------------------------------------------------------------------- a frame
  var state = { frame: 0, time: D.times[0], playing: false, speed: 1, last: null, shown: 0,
    timer: null };
  function pose(k) {
    for (var b = 0; b < nb; b++) {
      var i = 4 * (k * nb + b);
      frames[b].position.copy(vector(D.r, k * nb + b));
      frames[b].quaternion.set(D.p[i + 1], D.p[i + 2], D.p[i + 3], D.p[i]);  // x, y, z, w
      frames[b].updateMatrixWorld(true);
    }
    D.links.forEach(function (link, n) {
      var a = vector(link.a, 0).applyMatrix4(frameOf(link.body_a).matrixWorld);
      var c = vector(link.b, 0).applyMatrix4(frameOf(link.body_b).matrixWorld);
      linkPositions.set([a.x, a.y, a.z, c.x, c.y, c.z], 6 * n);
    });
    links.geometry.attributes.position.needsUpdate = true;
    vectors.forEach(function (v) {
      var value = vector(v.data.vector, k), length = value.length() * metresPer(v.data.unit);
      var at = v.data.origin;  // a path, or a point fixed in a body
      at = at.point ? vector(at.point, 0).applyMatrix4(frameOf(at.body).matrixWorld) : vector(at, k);
      pointArrow(v.group, at, value.normalize(), length);
      v.group.visible = v.group.visible && SHOWN[v.toggle];
    });
    trails.forEach(function (line, n) {
      line.geometry.setDrawRange(0, k + 1);
      line.children[0].position.copy(vector(D.trails[n].points, k));
    });
    var centre = vector(D.centres, k), radius = D.radii[k];
    var height = Math.max(0, centre.clone().sub(groundPoint).dot(groundUp));  // above the ground
    sun.target.position.copy(centre);
    sun.position.copy(centre).addScaledVector(up, 4 * radius).addScaledVector(across, radius)
      .addScaledVector(across2, 0.6 * radius);
    var box = sun.shadow.camera, half = 1.3 * radius + 0.4 * height;
    box.left = box.bottom = -half;
    box.right = box.top = half;
    box.near = 0.5 * radius;
    box.far = 6 * radius + 1.2 * height;
    box.updateProjectionMatrix();
  }
  function render() {
    fill.position.copy(camera.position);
    fill.target.position.copy(controls.target);
    renderer.render(scene, camera);
    labels.render(scene, camera);
    return renderer.info.render.triangles;
  }
  function show(k) {
    var target = followed(k), previous = followed(state.frame);
    if (target && previous) {
      var moved = target.sub(previous);
      controls.target.add(moved);
      camera.position.add(moved);
      controls.update();
    }
    state.frame = k;
    slider.value = String(k);
    timeLabel.textContent = 't = ' + D.times[k].toFixed(3) + ' s / ' +
      D.times[nFrames - 1].toFixed(3) + ' s';
    pose(k);
    var drawn = render();
    state.shown += 1;
    report('ok frame=' + k + ' of ' + nFrames + ' t=' + D.times[k] + ' triangles=' + drawn +
      ' shown=' + state.shown);
  }
  function applyShown() {
    document.querySelectorAll('[data-show]').forEach(function (box) {
      box.checked = SHOWN[box.dataset.show];
    });
    bodyLabels.forEach(function (tag) { tag.visible = SHOWN.bodies; });
    jointLabels.forEach(function (tag) { tag.visible = SHOWN.joints; });
    triads.forEach(function (group) { group.visible = SHOWN.frames; });
    contactShapes.forEach(function (mesh) { mesh.visible = SHOWN.shapes; });
    trails.forEach(function (line, n) {
      line.visible = SHOWN.trails && (D.trails[n].chosen || !D.trails.some(function (t) {
        return t.chosen;
      }));
    });
    floor.visible = grid.visible = SHOWN.grid;
    renderer.shadowMap.enabled = SHOWN.shadows;
    scene.traverse(function (object) { if (object.material) object.material.needsUpdate = true; });
    describeScales();
  }

  // ----------------------------------------------------------------------------- playback
  function frameAt(t) {  // last frame with time <= t
    var lo = 0, hi = nFrames - 1;
    while (lo < hi) {
      var mid = (lo + hi + 1) >> 1;
      if (D.times[mid] <= t) lo = mid; else hi = mid - 1;
    }
    return lo;
  }
  function nearestFrame(t) {
    var k = frameAt(t);
    return k + 1 < nFrames && D.times[k + 1] - t < t - D.times[k] ? k + 1 : k;
  }
  // Playback runs on a 60 Hz timer rather than requestAnimationFrame: the same in a browser
  // window, and it also advances under headless Chromium's virtual time (used by the tests).
  function setPlaying(on) {
    state.playing = on && nFrames > 1;
    playButton.textContent = state.playing ? 'Pause' : 'Play';
    state.last = null;
    window.clearTimeout(state.timer);
    if (state.playing) {
      if (state.frame === nFrames - 1) state.time = D.times[0];
      tick();
    }
  }
  function tick() {
    if (!state.playing) return;
    var now = window.performance.now();
    if (state.last !== null) {
      state.time += (now - state.last) / 1000 * state.speed;
      if (state.time > D.times[nFrames - 1]) state.time = D.times[0];  // loop
    }
    state.last = now;
    var k = frameAt(state.time);
    if (k !== state.frame) show(k);
    state.timer = window.setTimeout(tick, 1000 / 60);
  }
  function step(by) {
    setPlaying(false);
    var k = Math.max(0, Math.min(nFrames - 1, state.frame + by));
    state.time = D.times[k];
    show(k);
  }

  slider.max = String(nFrames - 1);
  slider.addEventListener('input', function () {
    var k = Number(slider.value);
    state.time = D.times[k];
    show(k);
  });
  playButton.addEventListener('click', function () { setPlaying(!state.playing); });
  speedSelect.addEventListener('change', function () { state.speed = Number(speedSelect.value); });
  document.getElementById('fit').addEventListener('click', function () {
    fit(state.frame); show(state.frame);
  });
  var menu = document.getElementById('menu');
  menu.addEventListener('click', function () {
    panel.hidden = !panel.hidden;
    menu.setAttribute('aria-expanded', String(!panel.hidden));
  });
  document.querySelectorAll('[data-show]').forEach(function (box) {
    box.addEventListener('change', function () {
      SHOWN[box.dataset.show] = box.checked;
      applyShown();
      show(state.frame);
    });
  });
  scaleSlider.addEventListener('input', function () { describeScales(); show(state.frame); });
  cameraSelect.addEventListener('change', function () {
    follow = cameraSelect.value;
    if (follow !== 'free') fit(state.frame);
    show(state.frame);
  });
  window.addEventListener('keydown', function (event) {
    var tag = event.target.tagName;
    if (tag === 'SELECT' || tag === 'INPUT' && event.target.type !== 'checkbox') return;
    if (event.key === ' ') { event.preventDefault(); setPlaying(!state.playing); }
    if (event.key === 'f' || event.key === 'F') { fit(state.frame); show(state.frame); }
    if (event.key === 'ArrowRight') step(1);
    if (event.key === 'ArrowLeft') step(-1);
  });
  window.addEventListener('resize', function () { resize(); show(state.frame); });

  var legend = document.getElementById('legend');
  Object.keys(VECTORS).forEach(function (kind) {
    if (!D.arrows.some(function (a) { return a.kind === kind; })) return;
    var item = document.createElement('div');
    var swatch = document.createElement('span');
    swatch.style.background = '#' + new T.Color(VECTORS[kind][1]).getHexString();
    item.appendChild(swatch);
    item.appendChild(document.createTextNode(kind.replace('_', ' ') + (VECTORS[kind][2] ? ' (double head)' : '')));
    legend.appendChild(item);
  });
  var gridNote = document.createElement('div');
  gridNote.textContent = 'grid: ' + step.toPrecision(3) + ' m';
  legend.appendChild(gridNote);

  // The URL's hash: #t=SECONDS shows the frame nearest that time, paused; besides it
  // show=a,b / hide=a,b (the panel's names: bodies, joints, frames, shapes, forces, torques,
  // motors, contacts, trails, grid, shadows), scale=LOG10, follow=free|mechanism|BODY and
  // view=EX,EY,EZ,TX,TY,TZ (camera position and target, global).
  function fromHash() {
    var hash = window.location.hash.replace(/^#/, ''), options = {};
    hash.split('&').forEach(function (item) {
      var at = item.indexOf('=');
      if (at > 0) options[decodeURIComponent(item.slice(0, at))] = decodeURIComponent(item.slice(at + 1));
    });
    ['show', 'hide'].forEach(function (key) {
      (options[key] || '').split(',').forEach(function (name) {
        if (name in SHOWN) SHOWN[name] = key === 'show';
      });
    });
    if (options.scale && isFinite(Number(options.scale))) scaleSlider.value = options.scale;
    if (D.bodies.indexOf(options.follow) >= 0) {  // a body's name first
      follow = 'body:' + options.follow;
    } else if (options.follow === 'free' || options.follow === 'mechanism') {
      follow = options.follow;
    }
    cameraSelect.value = follow;
    applyShown();
    var k = state.frame;
    var asked = options.t !== undefined && isFinite(Number(options.t));
    if (asked) {
      setPlaying(false);
      state.time = Number(options.t);
      k = nearestFrame(state.time);
    }
    var eye = (options.view || '').split(',').map(Number);
    if (eye.length === 6 && eye.every(isFinite)) {
      controls.target.set(eye[3], eye[4], eye[5]);
      camera.position.set(eye[0], eye[1], eye[2]);
      clip(camera.position.distanceTo(controls.target));
      follow = 'free';
      cameraSelect.value = follow;
    } else {
      fit(k, camera.position.lengthSq() > 0 ? null : vector(D.view, 0));
    }
    state.frame = k;
    show(k);
    return asked;
  }
  window.addEventListener('hashchange', fromHash);
  resize();
  if (!fromHash()) setPlaying(true);
})();
