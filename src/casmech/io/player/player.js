// casmech HTML player: a small Canvas2D renderer (painter's algorithm, flat shading), no network.
// Data (JSON in #casmech-data): parts (body-frame triangle surfaces), links, and per frame the
// CM position r and unit Euler parameters p of every body. x = r + A(p) x_bar.
(function () {
  'use strict';
  var status = document.getElementById('status');
  function report(text) { status.textContent = text; }
  window.addEventListener('error', function (event) {
    report('error: ' + (event.message || event.error));
  });

  var D = JSON.parse(document.getElementById('casmech-data').textContent);
  var canvas = document.getElementById('view');
  var ctx = canvas.getContext('2d');
  var slider = document.getElementById('slider');
  var playButton = document.getElementById('play');
  var timeLabel = document.getElementById('time');
  var speedSelect = document.getElementById('speed');
  var nb = D.bodies.length, nFrames = D.times.length;
  var PALETTE = [[66, 133, 244], [219, 68, 55], [244, 180, 0], [15, 157, 88], [171, 71, 188],
    [0, 172, 193], [255, 112, 67], [158, 157, 36], [92, 107, 192], [240, 98, 146]];
  var MARKER = [60, 60, 60];

  // ------------------------------------------------------------------ vectors and rotations
  function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
  function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
  function cross(a, b) {
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  }
  function unit(a) { var n = Math.sqrt(dot(a, a)) || 1; return [a[0] / n, a[1] / n, a[2] / n]; }
  function rotation(e0, e1, e2, e3) {  // A(p), row-major
    return [e0 * e0 + e1 * e1 - e2 * e2 - e3 * e3, 2 * (e1 * e2 - e0 * e3), 2 * (e1 * e3 + e0 * e2),
      2 * (e1 * e2 + e0 * e3), e0 * e0 - e1 * e1 + e2 * e2 - e3 * e3, 2 * (e2 * e3 - e0 * e1),
      2 * (e1 * e3 - e0 * e2), 2 * (e2 * e3 + e0 * e1), e0 * e0 - e1 * e1 - e2 * e2 + e3 * e3];
  }
  function poses(k) {  // [{A, r}] per body at frame k; index nb is ground
    var list = [];
    for (var b = 0; b < nb; b++) {
      var i = (k * nb + b) * 4, j = (k * nb + b) * 3;
      list.push({ A: rotation(D.p[i], D.p[i + 1], D.p[i + 2], D.p[i + 3]),
        r: [D.r[j], D.r[j + 1], D.r[j + 2]] });
    }
    list.push({ A: [1, 0, 0, 0, 1, 0, 0, 0, 1], r: [0, 0, 0] });
    return list;
  }
  function place(pose, x, y, z) {
    var A = pose.A, r = pose.r;
    return [r[0] + A[0] * x + A[1] * y + A[2] * z, r[1] + A[3] * x + A[4] * y + A[5] * z,
      r[2] + A[6] * x + A[7] * y + A[8] * z];
  }
  function poseOf(list, body) { return list[body < 0 ? nb : body]; }

  // ------------------------------------------------------------------------------ camera
  var up = unit(D.up);
  var side = unit(cross(up, Math.abs(up[0]) < 0.9 ? [1, 0, 0] : [0, 1, 0]));
  var side2 = cross(up, side);
  var camera = { yaw: Math.atan2(dot(D.view, side2), dot(D.view, side)),
    pitch: Math.asin(Math.max(-1, Math.min(1, dot(D.view, up)))), distance: 2.4 * D.radius };
  function view(width, height) {
    var cp = Math.cos(camera.pitch), sp = Math.sin(camera.pitch);
    var cy = Math.cos(camera.yaw), sy = Math.sin(camera.yaw);
    var back = [0, 1, 2].map(function (i) {
      return cp * (cy * side[i] + sy * side2[i]) + sp * up[i];
    });
    var eye = [0, 1, 2].map(function (i) { return D.center[i] + camera.distance * back[i]; });
    var forward = unit(sub(D.center, eye));
    var right = unit(cross(forward, up));
    var upward = cross(right, forward);
    var focal = 0.5 * Math.min(width, height) / Math.tan(0.5 * 0.7);  // 40 degrees
    var near = 1e-3 * camera.distance;
    return {
      eye: eye, forward: forward, light: unit([0, 1, 2].map(function (i) {
        return -forward[i] + 0.4 * upward[i] - 0.3 * right[i];
      })),
      project: function (x) {
        var d = sub(x, eye), z = dot(d, forward);
        return [width / 2 + focal * dot(d, right) / z, height / 2 - focal * dot(d, upward) / z,
          z, z > near];
      }
    };
  }

  // ------------------------------------------------------------------------------ drawing
  function colourOf(part) {
    return part.joint >= 0 ? MARKER : PALETTE[((part.body % 10) + 10) % 10];
  }

  function draw(k) {
    var dpr = window.devicePixelRatio || 1;
    var width = Math.max(1, Math.round(canvas.clientWidth * dpr));
    var height = Math.max(1, Math.round(canvas.clientHeight * dpr));
    if (canvas.width !== width || canvas.height !== height) {
      canvas.width = width; canvas.height = height;
    }
    var v = view(width, height), list = poses(k), faces = [];
    ctx.fillStyle = '#f4f5f7';
    ctx.fillRect(0, 0, width, height);
    drawAxes(v, dpr);
    D.parts.forEach(function (part) {
      var pose = poseOf(list, part.body), P = part.points, world = [], screen = [];
      for (var i = 0; i < P.length; i += 3) {
        var x = place(pose, P[i], P[i + 1], P[i + 2]);
        world.push(x); screen.push(v.project(x));
      }
      var colour = colourOf(part), T = part.triangles;
      for (var t = 0; t < T.length; t += 3) {
        var a = screen[T[t]], b = screen[T[t + 1]], c = screen[T[t + 2]];
        if (!(a[3] && b[3] && c[3])) continue;
        var n = cross(sub(world[T[t + 1]], world[T[t]]), sub(world[T[t + 2]], world[T[t]]));
        var length = Math.sqrt(dot(n, n));
        if (!(length > 0)) continue;
        var shade = 0.35 + 0.65 * Math.abs(dot(n, v.light)) / length;
        faces.push({ a: a, b: b, c: c, depth: (a[2] + b[2] + c[2]) / 3, colour: colour,
          shade: shade });
      }
    });
    faces.sort(function (f, g) { return g.depth - f.depth; });
    ctx.lineWidth = 0.6 * dpr;
    ctx.lineJoin = 'round';
    faces.forEach(function (f) {
      var s = f.shade, c = f.colour;
      var fill = 'rgb(' + Math.round(c[0] * s) + ',' + Math.round(c[1] * s) + ',' +
        Math.round(c[2] * s) + ')';
      ctx.fillStyle = fill; ctx.strokeStyle = fill;
      ctx.beginPath(); ctx.moveTo(f.a[0], f.a[1]); ctx.lineTo(f.b[0], f.b[1]);
      ctx.lineTo(f.c[0], f.c[1]); ctx.closePath(); ctx.fill(); ctx.stroke();
    });
    drawLinks(v, list, dpr);
    return faces.length;
  }

  function segment(v, a, b, colour, widthPx) {
    var p = v.project(a), q = v.project(b);
    if (!(p[3] && q[3])) return;
    ctx.strokeStyle = colour; ctx.lineWidth = widthPx;
    ctx.beginPath(); ctx.moveTo(p[0], p[1]); ctx.lineTo(q[0], q[1]); ctx.stroke();
  }
  function drawAxes(v, dpr) {  // global triad at the origin, a fifth of the scene
    var L = 0.2 * D.radius, o = [0, 0, 0];
    segment(v, o, [L, 0, 0], '#d33', 2 * dpr);
    segment(v, o, [0, L, 0], '#2a2', 2 * dpr);
    segment(v, o, [0, 0, L], '#33d', 2 * dpr);
  }
  function drawLinks(v, list, dpr) {
    D.links.forEach(function (link) {
      segment(v, place(poseOf(list, link.body_a), link.a[0], link.a[1], link.a[2]),
        place(poseOf(list, link.body_b), link.b[0], link.b[1], link.b[2]), '#333', 2 * dpr);
    });
  }

  // ----------------------------------------------------------------------------- playback
  var state = { frame: 0, time: D.times[0], playing: false, speed: 1, last: null, shown: 0,
    timer: null };
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
  function show(k) {
    state.frame = k;
    slider.value = String(k);
    timeLabel.textContent = 't = ' + D.times[k].toFixed(3) + ' s / ' +
      D.times[nFrames - 1].toFixed(3) + ' s';
    var drawn = draw(k);
    state.shown += 1;
    report('ok frame=' + k + ' of ' + nFrames + ' t=' + D.times[k] + ' triangles=' + drawn +
      ' shown=' + state.shown);
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

  slider.max = String(nFrames - 1);
  slider.addEventListener('input', function () {
    var k = Number(slider.value);
    state.time = D.times[k];
    show(k);
  });
  playButton.addEventListener('click', function () { setPlaying(!state.playing); });
  speedSelect.addEventListener('change', function () { state.speed = Number(speedSelect.value); });
  window.addEventListener('keydown', function (event) {
    if (event.key === ' ' && event.target.tagName !== 'SELECT') {
      event.preventDefault(); setPlaying(!state.playing);
    }
  });
  window.addEventListener('resize', function () { show(state.frame); });

  var drag = null;
  canvas.addEventListener('pointerdown', function (event) {
    drag = { x: event.clientX, y: event.clientY };
    canvas.setPointerCapture(event.pointerId);
  });
  canvas.addEventListener('pointermove', function (event) {
    if (!drag) return;
    camera.yaw -= 0.01 * (event.clientX - drag.x);
    camera.pitch = Math.max(-1.5, Math.min(1.5, camera.pitch + 0.01 * (event.clientY - drag.y)));
    drag = { x: event.clientX, y: event.clientY };
    if (!state.playing) show(state.frame);
  });
  canvas.addEventListener('pointerup', function () { drag = null; });
  canvas.addEventListener('wheel', function (event) {
    event.preventDefault();
    camera.distance *= Math.exp(0.001 * Math.max(-500, Math.min(500, event.deltaY)));
    camera.distance = Math.max(0.05 * D.radius, Math.min(50 * D.radius, camera.distance));
    if (!state.playing) show(state.frame);
  }, { passive: false });

  // #t=SECONDS shows the frame nearest that time, paused; otherwise play from the start
  function fromHash() {
    var asked = /(?:^#|&)t=([-+0-9.eE]+)/.exec(window.location.hash);
    if (!asked || !isFinite(Number(asked[1]))) return false;
    setPlaying(false);
    state.time = Number(asked[1]);
    show(nearestFrame(state.time));
    return true;
  }
  window.addEventListener('hashchange', fromHash);
  if (!fromHash()) {
    show(0);
    setPlaying(true);
  }
})();
