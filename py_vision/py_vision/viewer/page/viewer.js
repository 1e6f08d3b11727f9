"use strict";
/* WebCodecs, newer than the browser globals of the ESLint that lints this page. */
/* global VideoDecoder, EncodedVideoChunk */
(function () {
  const video = document.getElementById("video");
  const overlay = document.getElementById("overlay");
  const status = document.getElementById("status");
  let retry = null;

  function show(id, text) { document.getElementById(id).textContent = text; }
  function num(value, digits, unit) {
    return (typeof value === "number") ? value.toFixed(digits) + (unit || "") : "-";
  }
  function setStatus(text, cls) { status.textContent = text; status.className = cls; }

  const canvas = document.getElementById("canvas");
  // "mjpeg" (the img shows /stream) or "h264" (this page decodes /video itself, WebCodecs),
  // chosen from /stats: at the first answer (null until then, so nothing is fetched twice),
  // and again when the codec the node receives changes (chosenFor).
  let mode = null;
  let chosenFor = null;
  let player = null;   // the H.264 player while one runs: {stop}

  function connectVideo() {
    retry = null;
    if (mode === "h264") {
      player = playH264();
    } else if (mode === "mjpeg") {
      video.src = "/stream?t=" + Date.now();
    }
  }
  function disconnectVideo() {
    video.removeAttribute("src");
    if (player) { player.stop(); player = null; }
  }
  function message(text) { overlay.textContent = text; overlay.hidden = !text; }
  function videoLost() {
    message("video unavailable (too many viewers, or the node stopped); retrying");
    if (!retry && !document.hidden) { retry = setTimeout(connectVideo, 3000); }
  }
  video.addEventListener("error", videoLost);
  // A hidden tab stops its stream, so background tabs cost the robot nothing.
  document.addEventListener("visibilitychange", function () {
    if (document.hidden) { disconnectVideo(); } else { connectVideo(); }
  });

  // A camera's H.264, decoded here: where the browser has WebCodecs for it (a secure context:
  // this machine's viewer, or one reached through ssh -L), the node decodes nothing.
  async function canDecode(codec) {
    if (typeof VideoDecoder !== "function" || !codec) { return false; }
    try {
      return (await VideoDecoder.isConfigSupported({ codec: codec })).supported === true;
    } catch (e) {
      return false;
    }
  }

  async function chooseMode(s) {
    chosenFor = s.video_codec || "";
    disconnectVideo();
    const h264 = Boolean(s.video_codec) && await canDecode(s.video_codec);
    mode = h264 ? "h264" : "mjpeg";
    video.hidden = h264;
    canvas.hidden = !h264;
    if (!document.hidden) { connectVideo(); }
  }

  // GET /video: each access unit after a 5-byte header (length, big-endian; 1 where a
  // decoder can start). Units after a gap (too slow to keep up) wait for such a start.
  function playH264() {
    const abort = new AbortController();
    let stopped = false;
    const decoder = new VideoDecoder({
      output: function (picture) {
        if (canvas.width !== picture.displayWidth) { canvas.width = picture.displayWidth; }
        if (canvas.height !== picture.displayHeight) {
          canvas.height = picture.displayHeight;
        }
        canvas.getContext("2d").drawImage(picture, 0, 0);
        picture.close();
      },
      error: function () { if (!stopped) { abort.abort(); } },
    });
    (async function () {
      try {
        const response = await fetch("/video", { cache: "no-store", signal: abort.signal });
        if (!response.ok) { throw new Error(String(response.status)); }
        decoder.configure({ codec: response.headers.get("X-Video-Codec"),
                            optimizeForLatency: true });
        const reader = response.body.getReader();
        let buffer = new Uint8Array(0);
        let count = 0;
        let waiting = true;
        for (;;) {
          const chunk = await reader.read();
          if (chunk.done) { throw new Error("the stream ended"); }
          const joined = new Uint8Array(buffer.length + chunk.value.length);
          joined.set(buffer);
          joined.set(chunk.value, buffer.length);
          buffer = joined;
          while (buffer.length >= 5) {
            const length = new DataView(buffer.buffer, buffer.byteOffset).getUint32(0);
            if (buffer.length < 5 + length) { break; }
            const start = buffer[4] === 1;
            // A decoder that cannot keep up skips to the next start, as the node's does.
            if (decoder.decodeQueueSize > 30) { waiting = true; }
            if (start) { waiting = false; }
            if (!waiting) {
              decoder.decode(new EncodedVideoChunk({
                type: start ? "key" : "delta", timestamp: 1000 * count,
                data: buffer.subarray(5, 5 + length) }));
              count += 1;
            }
            buffer = buffer.slice(5 + length);
          }
        }
      } catch (e) {
        if (!stopped) { player = null; videoLost(); }
      } finally {
        if (decoder.state !== "closed") { decoder.close(); }
      }
    })();
    return { stop: function () { stopped = true; abort.abort(); } };
  }

  // One request at a time, one per second: the page never floods the server.
  async function poll() {
    try {
      const response = await fetch("/stats", { cache: "no-store" });
      if (!response.ok) { throw new Error(response.status); }
      const s = await response.json();
      show("stat-topic", s.topic || "-");
      show("stat-fps", num(s.fps, 1));
      show("stat-latency", num(s.latency_ms_p50, 1, " ms"));
      show("stat-latency-p99", num(s.latency_ms_p99, 1, " ms"));
      show("stat-resolution", (s.width && s.height) ? s.width + " \u00d7 " + s.height : "-");
      show("stat-encoding", s.encoding || "-");
      show("stat-frames", (typeof s.frames === "number") ? String(s.frames) : "-");
      show("stat-clients", String(s.clients));
      // A processing node (cv_bridge_test) also reports what it skipped and how long it took.
      const processing = typeof s.frames_in === "number";
      document.querySelectorAll(".proc").forEach(function (e) { e.hidden = !processing; });
      if (processing) {
        show("stat-in", String(s.frames_in));
        show("stat-processed", String(s.processed));
        show("stat-skipped", String(s.skipped));
        show("stat-processing", num(s.processing_ms_p50, 1, " ms"));
        show("stat-processing-p99", num(s.processing_ms_p99, 1, " ms"));
        show("stat-age", num(s.age_ms_p50, 1, " ms"));
        show("stat-age-p99", num(s.age_ms_p99, 1, " ms"));
      }
      // A video's units come but no keyframe has told its codec yet (video_codec ""): wait
      // for it. Choosing now would take the node's JPEG stream, which it decodes the video
      // for, until the next answer.
      const beforeKeyframe = s.video_codec === "";
      if (!beforeKeyframe && chosenFor !== (s.video_codec || "")) { chooseMode(s); }
      if (s.viewer_frames > 0 && mode === "mjpeg" && s.video_codec && s.video_decoder_missing) {
        setStatus("live", "live");
        message("this browser cannot decode the camera\u2019s H.264 here (it needs WebCodecs " +
                "in a secure context: open the viewer on localhost, e.g. through ssh -L), " +
                "and the node cannot either: " + s.video_decoder_missing);
      } else if (beforeKeyframe && mode === null) {
        setStatus("waiting for frames", "");
        message("waiting for the camera\u2019s next keyframe");
      } else if (s.viewer_frames > 0) {
        setStatus("live", "live");
        if (!retry) { message(""); }
      } else {
        setStatus("waiting for frames", "");
        message("waiting for the first frame");
      }
    } catch (e) {
      setStatus("disconnected", "down");
    }
    setTimeout(poll, 1000);
  }
  poll();

  // The camera panel: what the camera is and its controls, from GET /camera once a second
  // (a change made elsewhere shows within a second); a change is sent at once, and while a
  // slider moves at most one request per control is on its way. Controls are keyed by the
  // names the camera's node gives them, in Maps: a control may be called "constructor" or
  // "__proto__", which a plain object would take for its own machinery. The parameters of the
  // processing node's step (GET /camera's "step") are shown below in the same way, keyed
  // "step-" + name (no ROS name has a "-"), and set through POST /camera/step.
  const panel = document.getElementById("panel");
  const controlsBox = document.getElementById("controls");
  const stepBox = document.getElementById("step");
  const stepParameters = document.getElementById("step-parameters");
  const CAMERA = { prefix: "", route: "/camera/controls" };
  const STEP = { prefix: "step-", route: "/camera/step" };
  let layout = null;
  let stepLayout = null;
  const widgets = new Map();   // key: the control's elements
  const held = new Set();      // keys of the controls the user is moving now
  const queued = new Map();    // key: the value to send next
  const sending = new Set();   // keys with a request on its way

  function describeValue(c, value) {
    if (value === null || value === undefined) {
      return c.group === "step" ? "not set" : "camera\u2019s own value";
    }
    if (c.menu) {
      const entry = c.menu.find(function (m) { return m.value === value; });
      return entry ? entry.label : String(value);
    }
    if (typeof value === "boolean") { return value ? "on" : "off"; }
    return String(value);
  }

  function makeControl(name, c, where) {
    const key = where.prefix + name;
    const box = document.createElement("div");
    box.className = "control";
    box.id = "control-" + key;
    const label = document.createElement("label");
    label.textContent = name.replace(/_/g, " ");
    label.title = c.description || "";
    const value = document.createElement("span");
    value.className = "value";
    const note = document.createElement("span");
    note.className = "note";
    const why = document.createElement("span");
    why.className = "why";
    let input;
    if (c.menu) {
      // The menu shows the chosen entry itself: its label is not repeated beside the name.
      value.hidden = true;
      input = document.createElement("select");
      const own = document.createElement("option");
      own.value = "";
      own.textContent = describeValue(c, null);
      own.disabled = true;
      input.appendChild(own);
      c.menu.forEach(function (m) {
        const option = document.createElement("option");
        option.value = String(m.value);
        option.textContent = m.label;
        input.appendChild(option);
      });
    } else if (c.button) {
      // A button: pressing sends true; the camera's node reads it back false.
      value.hidden = true;
      input = document.createElement("button");
      input.type = "button";
      input.textContent = "press";
    } else if (c.type === "bool") {
      input = document.createElement("input");
      input.type = "checkbox";
    } else if (typeof c.min === "number" && typeof c.max === "number" &&
               c.max - c.min <= Number.MAX_SAFE_INTEGER) {
      input = document.createElement("input");
      input.type = "range";
      input.min = c.min;
      input.max = c.max;
      input.step = c.step > 0 ? c.step : (c.type === "integer" ? 1 : "any");
    } else {
      input = document.createElement("input");
      input.type = "text";
    }
    input.name = name;
    input.disabled = c.read_only;
    label.htmlFor = input.id = "input-" + key;
    input.addEventListener("pointerdown", function () { held.add(key); });
    const changed = c.button ? "click" : (input.type === "range" ? "input" : "change");
    input.addEventListener(changed, function () {
      let v;
      if (c.button) { v = true; }
      else if (input.type === "checkbox") { v = input.checked; }
      else if (c.type === "integer") { v = parseInt(input.value, 10); }
      else if (c.type === "double") { v = parseFloat(input.value); }
      else { v = input.value; }
      value.textContent = describeValue(c, v);
      send(key, name, v, where.route);
    });
    ["change", "pointerup", "pointercancel"].forEach(function (event) {
      input.addEventListener(event, function () { held.delete(key); });
    });
    if (input.type === "checkbox") {
      value.appendChild(document.createTextNode(""));
      const right = document.createElement("span");
      right.className = "value";
      right.append(value, input);
      box.append(label, right, why, note);
    } else {
      box.append(label, value, input, why, note);
    }
    widgets.set(key, { box: box, input: input, value: value, note: note, why: why, spec: c });
    return box;
  }

  function showValue(key, c) {
    const w = widgets.get(key);
    w.spec = c;
    w.box.classList.toggle("unset", c.value === null);
    w.box.classList.toggle("inactive", Boolean(c.inactive));
    w.why.textContent = c.inactive ? "inactive " + c.inactive
      : (c.read_only && c.group === "step" ? "read-only: set when the node starts" : "");
    w.value.textContent = describeValue(c, c.value);
    // A control being moved, or whose value is on its way to the node, keeps what the user
    // set: a poll answered before the node took the value would put the old one back.
    if (held.has(key) || queued.has(key) || sending.has(key)) { return; }
    if (w.input.type === "checkbox") {
      w.input.indeterminate = c.value === null;
      w.input.checked = c.value === true;
    } else if (w.input.tagName === "SELECT") {
      w.input.value = c.value === null ? "" : String(c.value);
    } else if (c.value !== null) {
      w.input.value = String(c.value);
    } else if (w.input.type === "range") {
      w.input.value = String((Number(c.min) + Number(c.max)) / 2);
    }
  }

  function renderCamera(cam) {
    panel.hidden = false;
    show("panel-message", cam.message || "");
    const info = cam.camera || {};
    const shown = cam.shown || {};
    show("cam-node", cam.publisher || "-");
    show("cam-device", info.device || "-");
    show("cam-format", info.pixel_format || "-");
    show("cam-size", info.size || shown.size || "-");
    const rates = [];
    if (typeof shown.fps === "number") { rates.push(shown.fps.toFixed(1) + " fps shown"); }
    if (typeof info.fps === "number") { rates.push(info.fps.toFixed(1) + " fps at the camera"); }
    show("cam-rate", rates.join(", ") || "-");
    show("cam-status", info.status || "-");
    // A control under a second name (usb_cam's) is shown once, under the camera's name.
    const all = new Map(Object.entries(cam.controls || {}));
    const controls = new Map();
    all.forEach(function (c, n) {
      if (!(c.alias_of && all.has(c.alias_of))) { controls.set(n, c); }
    });
    const key = layoutKey(controls);
    if (key !== layout) {
      layout = key;
      controlsBox.textContent = "";
      forget(CAMERA);
      let group = null;
      controls.forEach(function (c, n) {
        if (c.group !== group) {
          group = c.group;
          const h = document.createElement("h3");
          h.textContent = group === "stream" ? "stream settings" : "controls";
          controlsBox.appendChild(h);
        }
        controlsBox.appendChild(makeControl(n, c, CAMERA));
      });
    }
    controls.forEach(function (c, n) { showValue(n, c); });
    renderStep(cam.step);
  }

  // What decides the widgets: when it changes, they are made again.
  function layoutKey(controls) {
    return JSON.stringify(Array.from(controls, function ([n, c]) {
      return [n, c.type, c.min, c.max, c.step, c.menu, c.read_only, c.group, c.button];
    }));
  }

  function forget(where) {
    Array.from(widgets.keys()).forEach(function (key) {
      const isStep = key.startsWith(STEP.prefix);
      if (isStep === (where === STEP)) { widgets.delete(key); }
    });
  }

  // The step of the processing node the frames come through (or this viewer's own node's).
  function renderStep(step) {
    stepBox.hidden = !step;
    if (!step) { return; }
    show("step-title", "step " + (step.step || "") + " on " + step.node);
    show("step-message", step.message || "");
    const parameters = new Map(Object.entries(step.parameters || {}));
    const key = layoutKey(parameters);
    if (key !== stepLayout) {
      stepLayout = key;
      stepParameters.textContent = "";
      forget(STEP);
      parameters.forEach(function (c, n) {
        stepParameters.appendChild(makeControl(n, c, STEP));
      });
    }
    parameters.forEach(function (c, n) { showValue(STEP.prefix + n, c); });
  }

  async function send(key, name, v, route) {
    queued.set(key, v);
    if (sending.has(key)) { return; }
    sending.add(key);
    const w = widgets.get(key);
    while (queued.has(key)) {
      // fromEntries makes an own property of any name ("__proto__" too).
      const body = JSON.stringify(Object.fromEntries([[name, queued.get(key)]]));
      queued.delete(key);
      try {
        const response = await fetch(route, {
          method: "POST", cache: "no-store", body: body,
          headers: { "Content-Type": "application/json" } });
        const answer = await response.json();
        const results = new Map(Object.entries(response.ok ? answer.results : {}));
        const result = results.get(name) || { applied: false, reason: answer.error };
        if (w) { w.note.textContent = result.applied ? "" : "refused: " + result.reason; }
      } catch (e) {
        if (w) { w.note.textContent = "not sent: the viewer does not answer"; }
      }
    }
    sending.delete(key);
  }

  async function pollCamera() {
    try {
      const response = await fetch("/camera", { cache: "no-store" });
      if (response.status === 404) {  // no camera panel (yet): ask again now and then
        panel.hidden = true;
        setTimeout(pollCamera, 5000);
        return;
      }
      if (response.ok) { renderCamera(await response.json()); }
    } catch (e) {
      // the node stopped: the status line says so; keep trying
    }
    setTimeout(pollCamera, 1000);
  }
  pollCamera();

  function download(href) {
    const link = document.createElement("a");
    link.href = href;
    link.download = "snapshot-" + new Date().toISOString().replace(/[:.]/g, "-") + ".jpg";
    document.body.appendChild(link);
    link.click();
    link.remove();
  }
  document.getElementById("snapshot").addEventListener("click", function () {
    if (mode !== "h264") { download("/snapshot.jpg"); return; }
    // The picture this page decoded: the node has none to give.
    canvas.toBlob(function (blob) {
      const href = URL.createObjectURL(blob);
      download(href);
      setTimeout(function () { URL.revokeObjectURL(href); }, 1000);
    }, "image/jpeg", 0.9);
  });
})();
