// sdfc's WebGPU driver for a compiled scene: a plain ES module, no build step, no
// framework. It takes a GPUDevice, the module's WGSL, its manifest (sdfc compile
// --manifest; schemas/manifest.v1.json) and its textures' mip levels, and draws the
// scene with `vs_main` + `fs_main`, one colour target, under WebGPU's default limits.
// The bind group layout is built from the manifest's bindings whose `used_by` names
// the render entry points, and nothing else. A module with the multi-scale atlas pass
// (the manifest's `coarse`) also gets its compute pipeline, which `prepare` records
// before each draw, as the manifest says. Each view drawn gets its own render pipeline
// (the manifest's `pipeline_constants`).

const KINDS = {
  "uniform": { buffer: { type: "uniform" } },
  "storage-read": { buffer: { type: "read-only-storage" } },
  "storage-read-write": { buffer: { type: "storage" } },
  "texture-2d": { texture: { sampleType: "float", viewDimension: "2d" } },
  "sampler": { sampler: { type: "filtering" } },
};

/// The render entry points, whose bindings the scene's one bind group holds.
const RENDER = ["vs_main", "fs_main"];

export class SdfcScene {
  /// `textures[i]` holds texture i's mip levels (ImageBitmaps, level 0 first), in the
  /// manifest's `textures` order; `format` is the colour target's (an -srgb format).
  constructor(device, wgsl, manifest, textures, format) {
    this.device = device;
    this.code = wgsl;
    this.manifest = manifest;
    this.textures = textures;
    this.module = device.createShaderModule({ label: "sdfc scene", code: wgsl });
    const used = manifest.bindings.filter(
      (b) => b.group === 0 && b.used_by.some((e) => RENDER.includes(e)),
    );
    // With the multi-scale pass, the render group is also cs_coarse's: visible to
    // compute, and its writable `coarse` buffer to the fragment stage (not the vertex).
    this.coarse = manifest.coarse || null;
    const also = this.coarse ? GPUShaderStage.COMPUTE : 0;
    const layout = device.createBindGroupLayout({
      label: "sdfc render group",
      entries: used.map((b) => ({
        binding: b.binding,
        visibility: (b.kind === "storage-read-write" ? GPUShaderStage.FRAGMENT
          : GPUShaderStage.VERTEX | GPUShaderStage.FRAGMENT) | also,
        ...KINDS[b.kind],
      })),
    });
    this.globals = device.createBuffer({
      label: "sdfc globals",
      size: 16 * manifest.globals_layout.length,
      usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST,
    });
    const images = manifest.textures.map((t, i) => {
      const levels = textures[i];
      const texture = device.createTexture({
        label: t.path,
        size: [levels[0].width, levels[0].height],
        mipLevelCount: levels.length,
        format: t.format,
        usage: GPUTextureUsage.TEXTURE_BINDING | GPUTextureUsage.COPY_DST |
          GPUTextureUsage.RENDER_ATTACHMENT,
      });
      levels.forEach((bitmap, level) => {
        device.queue.copyExternalImageToTexture(
          { source: bitmap },
          { texture, mipLevel: level },
          [bitmap.width, bitmap.height],
        );
      });
      const sampler = device.createSampler({
        addressModeU: t.address_mode,
        addressModeV: t.address_mode,
        magFilter: t.filter.mag,
        minFilter: t.filter.min,
        mipmapFilter: t.filter.mipmap,
      });
      return { view: texture.createView(), sampler };
    });
    // The run-time parameters' block (the manifest's `params`), at its defaults.
    this.params = null;
    if (manifest.params && manifest.params.fields.length > 0) {
      this.params = device.createBuffer({
        label: "sdfc params",
        size: manifest.params.size,
        usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST,
      });
      this.setParams({});
    }
    let tables = null;
    if (manifest.tables && manifest.tables.length > 0) {
      tables = device.createBuffer({
        label: "sdfc tables",
        size: 4 * manifest.tables.length,
        usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST,
      });
      device.queue.writeBuffer(tables, 0, new Uint32Array(manifest.tables));
    }
    // The coarse samples: 16 bytes (the pass off, every pixel walks) until `prepare`
    // sizes them for a frame.
    const noSamples = this.coarse &&
      device.createBuffer({ label: "sdfc coarse (off)", size: 16, usage: GPUBufferUsage.STORAGE });
    const resource = (b, samples) => {
      if (b.name === "globals") return { buffer: this.globals };
      if (this.coarse && b.binding === this.coarse.binding) return { buffer: samples };
      if (b.name === "tables") return { buffer: tables };
      if (b.name === "params") return { buffer: this.params };
      const t = manifest.textures.findIndex((t) => t.texture_binding === b.binding);
      if (t >= 0) return images[t].view;
      const s = manifest.textures.findIndex((t) => t.sampler_binding === b.binding);
      if (s >= 0) return images[s].sampler;
      throw new Error(`no resource for binding ${b.name}`);
    };
    this.groupWith = (samples) => device.createBindGroup({
      layout,
      entries: used.map((b) => ({ binding: b.binding, resource: resource(b, samples) })),
    });
    this.group = this.groupWith(noSamples);
    const pipelineLayout = device.createPipelineLayout({ bindGroupLayouts: [layout] });
    // A render pipeline per view drawn, built at its first draw: the view (the
    // globals' resolution.w) is a pipeline constant (the manifest's
    // pipeline_constants), so that the driver compiles that view's code alone; fs_main
    // has no atlas AOV target, so that switch is off. A module without the constants
    // draws every view with one pipeline.
    const declared = new Set((manifest.pipeline_constants || []).map((c) => c.name));
    const perView = declared.has("SCENE_VIEW") && declared.has("SCENE_ATLAS_AOV");
    this.pipelines = new Map();
    this.pipelineFor = (view) => {
      const key = perView ? view : 0;
      if (!this.pipelines.has(key)) {
        const constants = perView ? { SCENE_VIEW: view, SCENE_ATLAS_AOV: 0 } : {};
        this.pipelines.set(key, device.createRenderPipeline({
          label: `sdfc scene, view ${key}`,
          layout: pipelineLayout,
          vertex: { module: this.module, entryPoint: "vs_main" },
          fragment: { module: this.module, entryPoint: "fs_main", targets: [{ format }], constants },
        }));
      }
      return this.pipelines.get(key);
    };
    this.view = 0;
    this.pipelineFor(0);
    if (this.coarse) {
      this.coarsePipeline = device.createComputePipeline({
        label: "sdfc coarse",
        layout: pipelineLayout,
        compute: { module: this.module, entryPoint: this.coarse.entry_point },
      });
    }
    // The frame the coarse samples were last sized for: { size, samples, group }.
    this.framed = null;
    this.fresh = false;
  }

  /// For a module with the multi-scale pass: records `cs_coarse` for a `width` x
  /// `height` frame into `encoder` (sizing the frame's buffer when the size changed),
  /// as the manifest's `coarse` says; the next `draw` reads its samples. Returns whether
  /// the pass runs: not without it, nor past the device's largest storage binding
  /// (then every pixel walks). A draw not preceded by `prepare` walks every pixel.
  prepare(encoder, width, height) {
    const c = this.coarse;
    this.fresh = false;
    if (!c) return false;
    const axis = (n) => Math.floor((Math.max(n, 1) + c.step - 2) / c.step) + 1;
    const [columns, rows] = [axis(width), axis(height)];
    const bytes = columns * rows * c.vec4s_per_sample * 16;
    if (bytes > this.device.limits.maxStorageBufferBindingSize) return false;
    if (!this.framed || this.framed.size !== `${width}x${height}`) {
      const samples = this.device.createBuffer({ label: "sdfc coarse", size: bytes, usage: GPUBufferUsage.STORAGE });
      if (this.framed) this.framed.samples.destroy();
      this.framed = { size: `${width}x${height}`, samples, group: this.groupWith(samples) };
    }
    const pass = encoder.beginComputePass({ label: "sdfc coarse" });
    pass.setPipeline(this.coarsePipeline);
    pass.setBindGroup(0, this.framed.group);
    pass.dispatchWorkgroups(
      Math.ceil(columns / c.workgroup_size[0]),
      Math.ceil(rows / c.workgroup_size[1]),
      1,
    );
    pass.end();
    this.fresh = true;
    return true;
  }

  /// Writes the run-time parameters' block: `values` maps a parameter's name (`time`
  /// for the time) to a number or an array; the others keep their defaults. Values
  /// must lie in each parameter's [min, max]: the step bounds hold only there.
  setParams(values) {
    if (!this.params) return;
    // The values set so far stay (a slider and the clock set one each).
    this.values = { ...(this.values || {}), ...values };
    const block = new Float32Array(this.manifest.params.size / 4);
    for (const f of this.manifest.params.fields) {
      const v = this.values[f.name] ?? f.default;
      block.set(Array.isArray(v) ? v : [v], f.offset / 4);
    }
    this.device.queue.writeBuffer(this.params, 0, block);
  }

  /// Writes the Globals block: nine vec4 (the manifest's `globals` say what each holds).
  setGlobals(globals) {
    this.device.queue.writeBuffer(this.globals, 0, new Float32Array(globals.flat()));
    // The view the next draw's pipeline is built for (resolution.w; the colour view
    // where that is not a view's number).
    const view = Math.round(globals[7][3]);
    this.view = Number.isInteger(view) && view >= 0 ? view : 0;
  }

  /// Records the full-screen draw into a render pass (with the multi-scale pass, the
  /// samples of the `prepare` just before it, else every pixel walks).
  draw(pass) {
    pass.setPipeline(this.pipelineFor(this.view));
    pass.setBindGroup(0, this.fresh ? this.framed.group : this.group);
    this.fresh = false;
    pass.draw(3);
  }
}

/// Fetches what `sdfc export-web` wrote beside the page: the WGSL, the manifest and the
/// textures' mip levels, decoded as data (no colour-space conversion, no premultiply).
export async function load(base) {
  const get = async (path) => {
    const r = await fetch(new URL(path, base));
    if (!r.ok) throw new Error(`${path}: ${r.status}`);
    return r;
  };
  const wgsl = await (await get("scene.wgsl")).text();
  const manifest = await (await get("manifest.json")).json();
  const web = await (await get("web.json")).json();
  const textures = await Promise.all(
    web.textures.map((t) =>
      Promise.all(
        t.levels.map(async (level) =>
          createImageBitmap(await (await get(level)).blob(), {
            colorSpaceConversion: "none",
            premultiplyAlpha: "none",
          })
        ),
      )
    ),
  );
  return { wgsl, manifest, web, textures };
}

const sub = (a, b) => a.map((x, i) => x - b[i]);
const scale = (a, k) => a.map((x) => x * k);
const dot = (a, b) => a.reduce((s, x, i) => s + x * b[i], 0);
const norm = (a) => scale(a, 1 / Math.hypot(...a));
const cross = (a, b) => [
  a[1] * b[2] - a[2] * b[1],
  a[2] * b[0] - a[0] * b[2],
  a[0] * b[1] - a[1] * b[0],
];

/// The camera fields of `globals` looking from `eye` at `target` (as sdfc's
/// Camera::look_at: right = forward × y, up = right × forward).
export function lookAt(globals, eye, target) {
  const forward = norm(sub(target, eye));
  const helper = Math.hypot(...cross(forward, [0, 1, 0])) < 1e-6 ? [0, 0, 1] : [0, 1, 0];
  const right = norm(cross(forward, helper));
  const up = cross(right, forward);
  globals[0] = [...eye, globals[0][3]];
  globals[1] = [...forward, globals[1][3]];
  globals[2] = [...right, 0];
  globals[3] = [...up, 0];
}

/// Orbit controls on `canvas`: drag to turn around the centre of the shape's bounds,
/// wheel to move nearer or farther; `changed()` is called after each move. Returns
/// `reset(bounds)`, which takes the camera now in `globals` and new bounds.
export function orbit(canvas, globals, bounds, changed) {
  let target, radius, yaw, pitch;
  // Takes the camera in `globals` and the centre of `bounds` as the orbit's.
  const reset = (bounds) => {
    target = scale(bounds[0].map((x, i) => x + bounds[1][i]), 0.5);
    const offset = sub(globals[0].slice(0, 3), target);
    radius = Math.hypot(...offset);
    yaw = Math.atan2(offset[0], offset[2]);
    pitch = Math.asin(Math.max(-1, Math.min(1, offset[1] / radius)));
  };
  reset(bounds);
  const place = () => {
    const dir = [Math.cos(pitch) * Math.sin(yaw), Math.sin(pitch), Math.cos(pitch) * Math.cos(yaw)];
    lookAt(globals, target.map((x, i) => x + dir[i] * radius), target);
    changed();
  };
  let last = null;
  canvas.addEventListener("pointerdown", (e) => {
    last = [e.clientX, e.clientY];
    canvas.setPointerCapture(e.pointerId);
  });
  canvas.addEventListener("pointerup", () => (last = null));
  canvas.addEventListener("pointermove", (e) => {
    if (!last) return;
    yaw -= (e.clientX - last[0]) * 0.01;
    pitch = Math.max(-1.5, Math.min(1.5, pitch + (e.clientY - last[1]) * 0.01));
    last = [e.clientX, e.clientY];
    place();
  });
  canvas.addEventListener("wheel", (e) => {
    e.preventDefault();
    radius *= Math.exp(e.deltaY * 0.001);
    place();
  }, { passive: false });
  return reset;
}

/// A scene shown in a canvas with orbit controls, whose scene can be swapped for a newer
/// build (`sdfc serve`) keeping the camera once the user has moved it.
export class SdfcView {
  /// Opens a WebGPU device and configures `canvas`; `size` ([width, height]) overrides
  /// the scene's size.
  static async open(canvas, size = null) {
    if (!navigator.gpu) throw new Error("this browser has no WebGPU");
    const adapter = await navigator.gpu.requestAdapter();
    if (!adapter) throw new Error("no WebGPU adapter");
    const device = await adapter.requestDevice();
    device.addEventListener("uncapturederror", (e) => console.error(`WebGPU: ${e.error.message}`));
    device.lost.then((info) => console.error(`WebGPU device lost: ${info.message}`));
    return new SdfcView(canvas, adapter, device, size);
  }

  constructor(canvas, adapter, device, size) {
    Object.assign(this, { canvas, adapter, device, size });
    this.context = canvas.getContext("webgpu");
    this.format = navigator.gpu.getPreferredCanvasFormat();
    this.srgb = `${this.format}-srgb`;
    // COPY_SRC: the canvas's own texture can be read back in the frame that draws it.
    this.context.configure({
      device,
      format: this.format,
      viewFormats: [this.srgb],
      alphaMode: "opaque",
      usage: GPUTextureUsage.RENDER_ATTACHMENT | GPUTextureUsage.COPY_SRC,
    });
    this.scene = null;
    this.globals = null;
    this.moved = false;
    this.messages = [];
  }

  /// Builds a scene from `load`'s data and, when its module compiles and its pipeline
  /// builds, shows it instead of the current one (keeping the camera once moved) and
  /// draws. Resolves to { ok, messages }: on failure the current scene stays.
  async swap({ wgsl, manifest, textures }) {
    this.device.pushErrorScope("validation");
    let scene = null;
    let thrown = null;
    try {
      scene = new SdfcScene(this.device, wgsl, manifest, textures, this.srgb);
    } catch (e) {
      thrown = e;
    }
    const error = await this.device.popErrorScope();
    const messages = scene ? (await scene.module.getCompilationInfo()).messages : [];
    const problem = thrown || error ||
      messages.find((m) => m.type === "error") && new Error("the module did not compile");
    if (problem) {
      return { ok: false, messages: [...messages, { type: "error", message: String(problem.message || problem) }] };
    }
    const fresh = manifest.scene.globals.map((v) => [...v]);
    if (this.size) [fresh[7][0], fresh[7][1]] = this.size;
    [this.canvas.width, this.canvas.height] = [fresh[7][0], fresh[7][1]];
    this.scene = scene;
    this.messages = messages;
    if (!this.globals) {
      this.globals = fresh;
      this.reorbit = orbit(this.canvas, this.globals, manifest.scene.bounds, () => {
        this.moved = true;
        requestAnimationFrame(() => this.frame());
      });
    } else {
      // In place: the orbit controls hold this array. The camera rows stay once moved.
      fresh.forEach((row, i) => {
        if (!(this.moved && i < 4)) this.globals[i] = row;
      });
      if (!this.moved) this.reorbit(manifest.scene.bounds);
    }
    this.frame();
    return { ok: true, messages };
  }

  /// Draws the scene into the canvas. With `read`, also copies the canvas's texture
  /// in the same frame and resolves to its pixels (RGBA, rows top first).
  frame(read = false) {
    const { device, scene, globals } = this;
    if (!scene) return Promise.resolve(null);
    scene.setGlobals(globals);
    const texture = this.context.getCurrentTexture();
    const encoder = device.createCommandEncoder();
    scene.prepare(encoder, texture.width, texture.height);
    const pass = encoder.beginRenderPass({
      colorAttachments: [{
        view: texture.createView({ format: this.srgb }),
        loadOp: "clear",
        storeOp: "store",
        clearValue: [0, 0, 0, 1],
      }],
    });
    scene.draw(pass);
    pass.end();
    let buffer = null;
    const [w, h] = [texture.width, texture.height];
    const row = Math.ceil((4 * w) / 256) * 256;
    if (read) {
      buffer = device.createBuffer({ size: row * h, usage: GPUBufferUsage.COPY_DST | GPUBufferUsage.MAP_READ });
      encoder.copyTextureToBuffer({ texture }, { buffer, bytesPerRow: row }, [w, h]);
    }
    device.queue.submit([encoder.finish()]);
    if (!read) return Promise.resolve(null);
    const bgra = texture.format.startsWith("bgra");
    return buffer.mapAsync(GPUMapMode.READ).then(() => {
      const data = new Uint8Array(buffer.getMappedRange());
      const out = new Uint8Array(4 * w * h);
      for (let y = 0; y < h; y++) out.set(data.subarray(y * row, y * row + 4 * w), 4 * w * y);
      if (bgra) for (let i = 0; i < out.length; i += 4) [out[i], out[i + 2]] = [out[i + 2], out[i]];
      buffer.unmap();
      return out;
    });
  }
}

/// The page's whole program: loads the scene beside the page and shows it in `canvas`
/// at the scene's size (or `size`, [width, height]), with orbit controls. Resolves to
/// the view (its `device`, `scene`, `globals`, and the compiler's `messages`).
export async function show(canvas, base = document.baseURI, size = null) {
  const view = await SdfcView.open(canvas, size);
  const shown = await view.swap(await load(base));
  if (!shown.ok) throw new Error(shown.messages.map((m) => `${m.type}: ${m.message}`).join("\n"));
  // `?view=N` shows another of the module's views (the manifest's `globals` list them:
  // 1 normal, 4 uv, 5 checker, 15 walked, ...) instead of the colour.
  const asked = new URL(location.href).searchParams.get("view");
  if (asked !== null && Number.isInteger(Number(asked))) {
    view.globals[7][3] = Number(asked);
    view.frame();
  }
  // A scene that reads `time` animates (`?still` keeps its first frame, for tests).
  if (!new URL(location.href).searchParams.has("still")) {
    const start = performance.now();
    const tick = (now) => {
      const params = view.scene && view.scene.manifest.params;
      if (params && params.fields.some((f) => f.name === "time")) {
        view.scene.setParams({ time: (now - start) / 1000 });
        view.frame();
      }
      requestAnimationFrame(tick);
    };
    requestAnimationFrame(tick);
  }
  return view;
}

/// Renders the scene's first frame into an rgba8unorm-srgb texture and reads it back:
/// the pixels (RGBA, rows top first), for tests.
export async function readPixels(device, scene, globals) {
  const [w, h] = [globals[7][0], globals[7][1]];
  const texture = device.createTexture({
    size: [w, h],
    format: "rgba8unorm-srgb",
    usage: GPUTextureUsage.RENDER_ATTACHMENT | GPUTextureUsage.COPY_SRC,
  });
  const row = Math.ceil((4 * w) / 256) * 256;
  const buffer = device.createBuffer({
    size: row * h,
    usage: GPUBufferUsage.COPY_DST | GPUBufferUsage.MAP_READ,
  });
  const probe = new SdfcScene(device, scene.code, scene.manifest, scene.textures, "rgba8unorm-srgb");
  probe.setGlobals(globals);
  const encoder = device.createCommandEncoder();
  probe.prepare(encoder, w, h);
  const pass = encoder.beginRenderPass({
    colorAttachments: [{ view: texture.createView(), loadOp: "clear", storeOp: "store", clearValue: [0, 0, 0, 1] }],
  });
  probe.draw(pass);
  pass.end();
  encoder.copyTextureToBuffer({ texture }, { buffer, bytesPerRow: row }, [w, h]);
  device.queue.submit([encoder.finish()]);
  await buffer.mapAsync(GPUMapMode.READ);
  const data = new Uint8Array(buffer.getMappedRange());
  const out = new Uint8Array(4 * w * h);
  for (let y = 0; y < h; y++) out.set(data.subarray(y * row, y * row + 4 * w), 4 * w * y);
  return out;
}
