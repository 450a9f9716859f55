// The browser check of compiled modules (tests/web.rs): for every module listed in
// modules.json (folders written by `sdfc export-web`), Tint compiles the WGSL with no
// message, and every entry point's pipeline builds with one bind group layout per
// group made from the manifest's bindings whose `used_by` names that entry point, on
// a device with WebGPU's default limits (no limit is requested). The compute entry
// points are built only for modules listed with `compute: true` (tests/web.rs says
// why). Sets
// window.sdfcCheck = { modules: [{ name, messages, errors, built, ms }] }, where
// `built` names the entry points whose pipelines were built.

const KINDS = {
  "uniform": { buffer: { type: "uniform" } },
  "storage-read": { buffer: { type: "read-only-storage" } },
  "storage-read-write": { buffer: { type: "storage" } },
  "texture-2d": { texture: { sampleType: "float", viewDimension: "2d" } },
  "sampler": { sampler: { type: "filtering" } },
};

function layouts(device, manifest, entries, visibility) {
  const groups = [[], []];
  for (const b of manifest.bindings) {
    if (b.used_by.some((e) => entries.includes(e))) {
      // WebGPU: a writable storage buffer is not visible to the vertex stage.
      const seen = b.kind === "storage-read-write" ? visibility & ~GPUShaderStage.VERTEX : visibility;
      groups[b.group].push({ binding: b.binding, visibility: seen, ...KINDS[b.kind] });
    }
  }
  return groups.map((entries) => device.createBindGroupLayout({ entries }));
}

async function check(device, { name, compute }) {
  const wgsl = await (await fetch(`${name}/scene.wgsl`)).text();
  const manifest = await (await fetch(`${name}/manifest.json`)).json();
  device.pushErrorScope("validation");
  const module = device.createShaderModule({ code: wgsl });
  const info = await module.getCompilationInfo();
  const errors = [];
  const built = [];
  const shaderError = await device.popErrorScope();
  if (shaderError) errors.push(`module: ${shaderError.message}`);
  // Every pipeline at once (the browser may compile them in parallel), each in its
  // own error scope.
  await Promise.all(manifest.entry_points.map(async (ep) => {
    if (ep.name === "vs_main" || (ep.stage === "compute" && !compute)) return;
    const targets = ep.stage === "compute"
      ? null
      : manifest.render_targets.find((t) => t.entry === ep.name);
    // fs_aov needs more than the default maxColorAttachmentBytesPerSample: only fs_main
    // is built on this default-limits device (the manifest says which needs what).
    if (targets && targets.bytes_per_sample > device.limits.maxColorAttachmentBytesPerSample) {
      return;
    }
    built.push(ep.name);
    device.pushErrorScope("validation");
    const created = ep.stage === "compute"
      ? device.createComputePipelineAsync({
        layout: device.createPipelineLayout({
          bindGroupLayouts: layouts(device, manifest, [ep.name], GPUShaderStage.COMPUTE),
        }),
        compute: { module, entryPoint: ep.name },
      })
      : device.createRenderPipelineAsync({
        layout: device.createPipelineLayout({
          bindGroupLayouts: layouts(
            device, manifest, ["vs_main", ep.name], GPUShaderStage.VERTEX | GPUShaderStage.FRAGMENT,
          ),
        }),
        vertex: { module, entryPoint: "vs_main" },
        fragment: { module, entryPoint: ep.name, targets: targets.formats.map((format) => ({ format })) },
      });
    const e = device.popErrorScope();
    await created.catch((err) => errors.push(`${ep.name}: ${err.message}`));
    const scoped = await e;
    if (scoped) errors.push(`${ep.name}: ${scoped.message}`);
  }));
  return { name, messages: info.messages.map((m) => `${m.type}: ${m.message}`), errors, built };
}

// Two lanes, each with its own adapter and device (an error scope belongs to one device,
// so the lanes' scopes never interleave), take the modules from one queue: Tint and
// SwiftShader then compile two modules at once.
const LANES = 2;

async function lane(queue, modules) {
  const adapter = await navigator.gpu.requestAdapter();
  // Default limits: nothing is requested.
  const device = await adapter.requestDevice();
  window.keep.push({ adapter, device });
  while (queue.length > 0) {
    const item = queue.shift();
    const t = performance.now();
    const m = await check(device, item);
    m.ms = Math.round(performance.now() - t);
    modules.push(m);
  }
  return device.limits.maxColorAttachmentBytesPerSample;
}

try {
  window.keep = [];
  const queue = await (await fetch("modules.json")).json();
  const modules = [];
  const limits = await Promise.all(Array.from({ length: LANES }, () => lane(queue, modules)));
  window.sdfcCheck = { modules, maxColorAttachmentBytesPerSample: Math.min(...limits) };
  window.sdfcReady = true;
} catch (e) {
  window.sdfcError = String(e);
}
