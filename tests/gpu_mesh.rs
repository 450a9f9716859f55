//! The mesh renderer (`sdfc::gpu::MeshRenderer`) on hand-made flat seamless atlases:
//! quads facing the camera, one chart each, whose texels at every level are an
//! analytic function of the chart-local position at that level's half-texel-inset
//! sample points. GPU tests skip loudly without an adapter, and fail instead when
//! SDFC_REQUIRE_GPU=1.

use glam::DVec3;
use sdfc::bake::{FlatLayout, MeshData, Textures};
use sdfc::codegen::mesh::mesh_wgsl;
use sdfc::gpu::{check_layout, gpu_for_tests, Frame, Gpu, MeshError, MeshRenderer, ViewMode};
use sdfc::view::{Camera, View};

/// The blue of every chart's colour.
const BLUE: f64 = 0.25;
/// What the atlas holds outside the charts: a colour no chart has.
const UNUSED: [u8; 4] = [255, 0, 255, 255];

fn srgb_encode(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

fn byte(x: f64) -> u8 {
    (srgb_encode(x) * 255.0).round() as u8
}

/// `tonemap` of shaders/render.wgsl.
fn tonemap(c: f64) -> f64 {
    c / (1.0 + c * 0.15)
}

/// The linear base colour at a point of the strip: x ∈ [0, 1] across all the charts,
/// v down each chart. Continuous across the charts' shared edges.
fn analytic(x: f64, v: f64) -> [f64; 3] {
    [x, v, BLUE]
}

/// A strip of `charts` unit quads side by side in the plane z = 0 (chart c covers
/// x ∈ [c, c + 1], y ∈ [0, 1]; its v runs down, from y = 1 to y = 0), facing +z,
/// with a `size`² flat atlas whose base colour is [`analytic`] at every level's sample
/// points, and a flat normal map of bitangent sign `w`.
fn strip(charts: usize, size: u32, w: f32) -> (MeshData, Textures, FlatLayout) {
    let layout = FlatLayout::fit(charts, size).expect("the charts fit");
    let mut mesh = MeshData::default();
    for c in 0..charts {
        let base = mesh.positions.len() as u32;
        for (u, v) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
            mesh.positions
                .push([(c as f64 + u) as f32, (1.0 - v) as f32, 0.0]);
            mesh.normals.push([0.0, 0.0, 1.0]);
            mesh.tangents.push([1.0, 0.0, 0.0, w]);
            mesh.texcoords.push(layout.texcoord(c, u, v));
        }
        // Counter-clockwise seen from +z.
        mesh.indices
            .extend([base, base + 3, base + 2, base, base + 2, base + 1]);
    }
    let mut color = image::RgbaImage::from_pixel(layout.width, layout.height, image::Rgba(UNUSED));
    for c in 0..charts {
        for l in 0..layout.levels() {
            let n = layout.size_at(l);
            let [ox, oy] = layout.chart_origin(c, l);
            for j in 0..n {
                for i in 0..n {
                    let u = i as f64 / (n - 1) as f64;
                    let v = j as f64 / (n - 1) as f64;
                    let [r, g, b] = analytic((c as f64 + u) / charts as f64, v);
                    color.put_pixel(
                        ox + i,
                        oy + j,
                        image::Rgba([byte(r), byte(g), byte(b), 255]),
                    );
                }
            }
        }
    }
    let flat = |rgba: [u8; 4]| {
        image::RgbaImage::from_pixel(layout.width, layout.height, image::Rgba(rgba))
    };
    let textures = Textures {
        base_color: color,
        metallic_roughness: flat([0, 128, 0, 255]),
        normal: flat([128, 128, 255, 255]),
        emissive: None,
        emissive_strength: 1.0,
    };
    (mesh, textures, layout)
}

/// A `side`-pixel square view looking at the strip's centre down -z from `distance`.
fn view(charts: usize, distance: f64, side: u32) -> View {
    let centre = DVec3::new(charts as f64 * 0.5, 0.5, 0.0);
    let mut view = View::framing(sdfc::ir::Aabb {
        min: DVec3::ZERO,
        max: DVec3::new(charts as f64, 1.0, 0.0),
    });
    view.camera = Camera::look_at(
        centre + DVec3::Z * distance,
        centre,
        std::f64::consts::FRAC_PI_4,
    );
    view.width = side;
    view.height = side;
    view.far = distance * 4.0;
    view
}

/// The distance at which a unit of the plane spans `pixels` pixels.
fn distance_for(pixels: f64, side: u32) -> f64 {
    side as f64 / (pixels * 2.0 * (std::f64::consts::FRAC_PI_8).tan())
}

/// Where the ray through pixel (x, y) meets the plane z = 0, when it meets the strip
/// at least `margin` (world units) inside it.
fn hit(view: &View, charts: usize, x: u32, y: u32, margin: f64) -> Option<DVec3> {
    let c = &view.camera;
    let d = c.ray(
        x as f64 + 0.5,
        y as f64 + 0.5,
        view.width as f64,
        view.height as f64,
    );
    let p = c.eye + d * (-c.eye.z / d.z);
    let inside = p.x > margin && p.x < charts as f64 - margin && p.y > margin && p.y < 1.0 - margin;
    inside.then_some(p)
}

/// The largest difference, in bytes, between the albedo view and [`analytic`] through
/// the tone curve, over the pixels at least `margin` inside the strip; and how many.
fn albedo_error(frame: &Frame, view: &View, charts: usize, margin: f64) -> (u8, usize) {
    let mut worst = 0;
    let mut count = 0;
    for y in 0..frame.height {
        for x in 0..frame.width {
            let Some(p) = hit(view, charts, x, y, margin) else {
                continue;
            };
            let expected = analytic(p.x / charts as f64, 1.0 - p.y);
            let i = (y * frame.width + x) as usize * 4;
            for (k, e) in expected.into_iter().enumerate() {
                worst = worst.max(frame.color[i + k].abs_diff(byte(tonemap(e))));
            }
            count += 1;
        }
    }
    (worst, count)
}

/// Eq. 1–2 for a fronto-parallel quad of unit side at `distance`: the level the
/// shader should pick, clamped.
fn expected_level(layout: &FlatLayout, distance: f64, side: u32) -> f64 {
    let n = layout.chart_size as f64;
    let du_dx = distance * 2.0 * (std::f64::consts::FRAC_PI_8).tan() / side as f64;
    let l = (n * du_dx).log2();
    let i = l - (1.0 + l.exp2() / n).log2();
    // The defining property: one texel of level i per pixel, counting the half-texel
    // inset (level i spans n/2^i − 1 spacings over the chart), i.e. the paper's own
    // i = l + log2(1 − 2^i/N) (its printed Eq. 2 flips the sign of the solution).
    let texels_per_pixel = (n / i.exp2() - 1.0) * du_dx;
    assert!((texels_per_pixel - 1.0).abs() < 1e-9, "{texels_per_pixel}");
    assert!((i - (l + (1.0 - i.exp2() / n).log2())).abs() < 1e-9);
    i.clamp(0.0, (layout.levels() - 1) as f64)
}

/// The level AOV (atlas.z) over the pixels well inside the strip: (min, max).
fn levels_seen(frame: &Frame, view: &View, charts: usize) -> (f64, f64) {
    let mut range = (f64::INFINITY, f64::NEG_INFINITY);
    for y in 0..frame.height {
        for x in 0..frame.width {
            if hit(view, charts, x, y, 0.05).is_some() {
                let l = frame.atlas[(y * frame.width + x) as usize][2] as f64;
                range = (range.0.min(l), range.1.max(l));
            }
        }
    }
    range
}

fn renderer(gpu: &Gpu, charts: usize, size: u32, w: f32) -> (MeshRenderer, FlatLayout) {
    let (mesh, textures, layout) = strip(charts, size, w);
    (
        MeshRenderer::new(gpu, &mesh, &textures, &layout.clone().into()).unwrap(),
        layout,
    )
}

#[test]
fn the_mesh_module_validates_for_several_layouts() {
    let layouts = [
        FlatLayout::fit(1, 64),
        FlatLayout::fit(2, 256),
        FlatLayout::fit(7, 1000),
        FlatLayout::fit(100, 4096),
        // Charts of 2 texels: one level.
        FlatLayout::fit(600, 64),
    ];
    for layout in layouts {
        let layout = layout.expect("the charts fit");
        check_layout(&layout).unwrap();
        let wgsl = mesh_wgsl(&layout.clone().into()).unwrap();
        if let Err(e) = sdfc::codegen::validate(&wgsl) {
            panic!("{layout:?}:\n{e}");
        }
        let standard = sdfc::codegen::mesh::mesh_wgsl_with(
            &layout.clone().into(),
            sdfc::gpu::MeshFilter::Standard,
            2.5,
        )
        .unwrap();
        assert!(standard.contains("const STANDARD: bool = true;"));
        assert!(standard.contains("const EMISSIVE_STRENGTH: f32 = 2.5;"));
        assert!(wgsl.contains("const EMISSIVE_STRENGTH: f32 = 1.0;"));
        if let Err(e) = sdfc::codegen::validate(&standard) {
            panic!("{layout:?}, standard filter:\n{e}");
        }
        let origins = layout
            .level_origins
            .iter()
            .map(|[x, y]| format!("vec2<f32>({x}.0, {y}.0)"));
        for o in origins {
            assert!(wgsl.contains(&o), "{o} is not in the module");
        }
    }
}

#[test]
fn malformed_layouts_are_refused() {
    let good = FlatLayout::fit(3, 256).unwrap();
    let mut tiny = good.clone();
    tiny.chart_size = 1;
    assert!(check_layout(&tiny).is_err());
    let mut deep = good.clone();
    deep.level_origins.push([0, 0]);
    assert!(check_layout(&deep).unwrap_err().contains("levels"));
    let mut outside = good.clone();
    outside.level_origins[2][0] = 250;
    assert!(check_layout(&outside).unwrap_err().contains("level 2"));
    let mut none = good.clone();
    none.level_origins.clear();
    assert!(check_layout(&none).is_err());
}

#[test]
fn albedo_is_the_analytic_colour_at_level_0_and_at_coarse_levels() {
    let Some(gpu) = gpu_for_tests() else { return };
    let (r, layout) = renderer(&gpu, 1, 256, 1.0);
    assert_eq!((layout.chart_size, layout.levels()), (128, 7));
    // Close: 150 pixels a unit, more than the chart's 128 texels, so level 0. Coarse:
    // 20 and 10 pixels a unit, levels 2–3 and 3–4 (Eq. 2: 2.61 and 3.54).
    for (side, pixels, levels) in [
        (128, 150.0, (0.0, 0.0)),
        (64, 20.0, (2.0, 3.0)),
        (64, 10.0, (3.0, 4.0)),
    ] {
        let v = view(1, distance_for(pixels, side), side);
        let frame = r.render(&gpu, &v, ViewMode::Albedo).unwrap();
        let (worst, count) = albedo_error(&frame, &v, 1, 1.0 / pixels);
        assert!(
            count as f64 > 0.8 * (pixels - 2.0).min(side as f64).powi(2),
            "{count} pixels"
        );
        // 8-bit texels and an 8-bit image, both sRGB: a byte or two.
        assert!(worst <= 3, "{pixels} pixels a unit: off by {worst} bytes");
        let (lo, hi) = levels_seen(&frame, &v, 1);
        assert!(
            lo >= levels.0 && hi <= levels.1,
            "{pixels} pixels a unit: levels {lo}..{hi}"
        );
    }
}

#[test]
fn the_level_follows_eq_2_with_distance() {
    let Some(gpu) = gpu_for_tests() else { return };
    let (r, layout) = renderer(&gpu, 1, 256, 1.0);
    let side = 64;
    let mut last = -1.0;
    for pixels in [200.0, 100.0, 60.0, 32.0, 16.0, 8.0, 4.0] {
        let v = view(1, distance_for(pixels, side), side);
        let expected = expected_level(&layout, v.camera.eye.z, side);
        let frame = r.render(&gpu, &v, ViewMode::Level).unwrap();
        let (lo, hi) = levels_seen(&frame, &v, 1);
        assert!(
            (lo - expected).abs() < 0.01 && (hi - expected).abs() < 0.01,
            "{pixels} pixels a unit: levels {lo}..{hi}, Eq. 2 says {expected}"
        );
        assert!(expected >= last, "{expected} after {last}");
        last = expected;
        // The level view's ramp at the centre pixel.
        let centre = ((side / 2) * side + side / 2) as usize * 4;
        let t = expected / (layout.levels() - 1) as f64 * 4.0;
        let ramp = [3.0, 2.0, 1.0].map(|k: f64| byte((1.5 - (t - k).abs()).clamp(0.0, 1.0)));
        for k in 0..3 {
            assert!(
                frame.color[centre + k].abs_diff(ramp[k]) <= 2,
                "{pixels}: {:?} vs {ramp:?}",
                &frame.color[centre..centre + 3]
            );
        }
    }
    assert!(last >= 4.0, "the far quad reached level {last} only");
}

#[test]
fn two_charts_sharing_an_edge_show_no_seam() {
    let Some(gpu) = gpu_for_tests() else { return };
    let (r, layout) = renderer(&gpu, 2, 256, 1.0);
    assert_eq!((layout.chart_size, layout.columns), (128, 2));
    for (side, pixels) in [(128, 60.0), (64, 12.0)] {
        let v = view(2, distance_for(pixels, side), side);
        let frame = r.render(&gpu, &v, ViewMode::Albedo).unwrap();
        let (worst, _) = albedo_error(&frame, &v, 2, 1.0 / pixels);
        assert!(worst <= 3, "{pixels} pixels a unit: off by {worst} bytes");
        // Steps between horizontal neighbours: across the shared edge x = 1, and inside.
        let (mut across, mut inside) = (0u8, 0u8);
        for y in 0..frame.height {
            for x in 0..frame.width - 1 {
                let (Some(a), Some(b)) = (hit(&v, 2, x, y, 0.02), hit(&v, 2, x + 1, y, 0.02))
                else {
                    continue;
                };
                let i = (y * frame.width + x) as usize * 4;
                let step = (0..3)
                    .map(|k| frame.color[i + k].abs_diff(frame.color[i + 4 + k]))
                    .max()
                    .unwrap();
                if (a.x < 1.0) != (b.x < 1.0) {
                    across = across.max(step);
                } else {
                    inside = inside.max(step);
                }
            }
        }
        assert!(across > 0 || inside == 0, "the edge was not crossed");
        assert!(
            across <= inside + 1,
            "{pixels} pixels a unit: a step of {across} across the edge, {inside} inside"
        );
    }
}

#[test]
fn the_normal_map_is_read_in_the_tangent_frame() {
    let Some(gpu) = gpu_for_tests() else { return };
    // A normal tilted towards +T and +B: (0.6, 0.48, 0.64) in tangent space.
    let tilted = [0.6f64, 0.48, 0.64];
    let encoded = tilted.map(|c| ((c * 0.5 + 0.5) * 255.0).round() as u8);
    for w in [1.0f32, -1.0] {
        let (mesh, mut textures, layout) = strip(1, 64, w);
        textures.normal = image::RgbaImage::from_pixel(
            layout.width,
            layout.height,
            image::Rgba([encoded[0], encoded[1], encoded[2], 255]),
        );
        let r = MeshRenderer::new(&gpu, &mesh, &textures, &layout.clone().into()).unwrap();
        let v = view(1, distance_for(40.0, 32), 32);
        let frame = r.render(&gpu, &v, ViewMode::Normal).unwrap();
        let n = frame.normal[(16 * 32 + 16) as usize];
        // T = +x, N = +z, B = (N × T) · w = +y · w.
        let decoded = encoded.map(|c| c as f64 / 255.0 * 2.0 - 1.0);
        let len = decoded.iter().map(|c| c * c).sum::<f64>().sqrt();
        let expected = [
            decoded[0] / len,
            decoded[1] * w as f64 / len,
            decoded[2] / len,
        ];
        for k in 0..3 {
            assert!(
                (n[k] as f64 - expected[k]).abs() < 1e-3,
                "w = {w}: {n:?} vs {expected:?}"
            );
        }
        // The position AOV: the world point and its distance from the eye.
        let p = frame.position[(16 * 32 + 16) as usize];
        assert!(
            (p[3] as f64 - v.camera.eye.z).abs() < 1e-3 * v.camera.eye.z,
            "{p:?}"
        );
    }
}

/// On the default adapter and on llvmpipe's GL backend, whose AOV targets are
/// rgba32uint (`fs_bits`, cleared to the bits of the same floats).
#[test]
fn a_mesh_refuses_views_it_has_not_and_inconsistent_input() {
    for gpu in crate::common::both_for_tests() {
        refuses_on(&gpu);
    }
}

fn refuses_on(gpu: &Gpu) {
    let (mesh, textures, layout) = strip(1, 64, 1.0);
    let mut short = mesh.clone();
    short.tangents.pop();
    let mut small = textures.clone();
    small.normal = image::RgbaImage::new(32, 32);
    // An emissive strength the shader cannot hold is the caller's input, not an
    // internal error (it would have reached the WGSL as a literal NaN).
    let mut undefined = textures.clone();
    undefined.emissive_strength = f32::NAN;
    let mut negative = textures.clone();
    negative.emissive_strength = -1.0;
    for (m, t) in [
        (&short, &textures),
        (&mesh, &small),
        (&mesh, &undefined),
        (&mesh, &negative),
    ] {
        match MeshRenderer::new(gpu, m, t, &layout.clone().into()) {
            Err(MeshError::Input(_)) => {}
            Err(e) => panic!("{e}"),
            Ok(_) => panic!("accepted"),
        }
    }
    let r = MeshRenderer::new(gpu, &mesh, &textures, &layout.clone().into()).unwrap();
    let v = view(1, 2.0, 16);
    assert_eq!(
        r.render(gpu, &v, ViewMode::Steps).unwrap_err(),
        MeshError::View(ViewMode::Steps)
    );
    // Background where the quad is not.
    let v = view(1, 20.0, 16);
    let frame = r.render(gpu, &v, ViewMode::Color).unwrap();
    let bg = v.background.to_array().map(|c| byte(tonemap(c)));
    assert!(
        frame.color[..3]
            .iter()
            .zip(bg)
            .all(|(a, b)| a.abs_diff(b) <= 1),
        "{:?} vs {bg:?}",
        &frame.color[..3]
    );
    // The AOVs' clear values (as bits, where the targets are rgba32uint).
    assert_eq!(frame.position[0], [0.0, 0.0, 0.0, -1.0]);
    assert_eq!(frame.normal[0], [0.0; 4]);
    assert_eq!(frame.atlas[0], [0.0, 0.0, -1.0, -1.0]);
}

#[test]
fn the_mesh_and_the_implicit_scene_agree_in_the_albedo_and_colour_views() {
    let Some(gpu) = gpu_for_tests() else { return };
    // The plane z = 0 painted with the strip's colour (x, 1 − y, 0.25) and the strip's
    // roughness (128/255) and metallic (0).
    let src = "let ground = plane(normal: [0, 0, 1], offset: 0);\nmaterial m { color = [position.x, 1 - position.y, 0.25]; roughness = 0.50196078; metallic = 0; }\nrender ground.paint(m);";
    let a = sdfc::driver::check_all(src, None);
    assert!(!a.has_errors(), "{:?}", a.diagnostics);
    let module = a
        .compiled
        .as_ref()
        .expect("a validated module")
        .module
        .clone();
    let (r, _) = renderer(&gpu, 1, 256, 1.0);
    for (side, pixels) in [(64, 80.0), (64, 24.0)] {
        let v = view(1, distance_for(pixels, side), side);
        for mode in [ViewMode::Albedo, ViewMode::Color] {
            let mesh = r.render(&gpu, &v, mode).unwrap();
            let scene =
                sdfc::gpu::render(&gpu, &module, &v, mode, std::path::Path::new(".")).unwrap();
            let (mut worst, mut count, mut sum) = (0, 0, 0u64);
            for y in 0..side {
                for x in 0..side {
                    if hit(&v, 1, x, y, 1.0 / pixels).is_none() {
                        continue;
                    }
                    let i = (y * side + x) as usize * 4;
                    count += 1;
                    sum += mesh.color[i..i + 3].iter().map(|&c| c as u64).sum::<u64>();
                    for k in 0..3 {
                        worst = worst.max(mesh.color[i + k].abs_diff(scene.color[i + k]));
                    }
                }
            }
            let mean = sum / (3 * count as u64).max(1);
            eprintln!("{mode:?} at {pixels} pixels a unit: {count} pixels, mean byte {mean}, off by {worst} at most");
            assert!(count > 300 && mean > 30, "{count} pixels, mean byte {mean}");
            assert!(
                worst <= 2,
                "{mode:?} at {pixels} pixels a unit: off by {worst} bytes"
            );
        }
    }
}

/// Emission over 1 (`Textures::emissive_strength`, glTF's
/// KHR_materials_emissive_strength): the mesh's colour view, with the emissive texture
/// holding the emission divided by the strength, matches the implicit scene's within
/// the 8-bit texture's rounding (×1.8); the texture clipped at 1 instead does not
/// (12 bytes off on lavapipe, after the tone curve).
#[test]
fn emission_over_1_is_carried_by_the_strength() {
    let Some(gpu) = gpu_for_tests() else { return };
    let emission = [0.6f32, 1.8, 0.3];
    let src = format!(
        "let ground = plane(normal: [0, 0, 1], offset: 0);\nmaterial m {{ color = [position.x, 1 - position.y, 0.25]; roughness = 0.50196078; metallic = 0; emission = {emission:?}; }}\nrender ground.paint(m);"
    );
    let a = sdfc::driver::check_all(&src, None);
    assert!(!a.has_errors(), "{:?}", a.diagnostics);
    let module = a.compiled.as_ref().expect("a module").module.clone();
    let side = 64;
    let v = view(1, distance_for(80.0, side), side);
    let scene = sdfc::gpu::render(
        &gpu,
        &module,
        &v,
        ViewMode::Color,
        std::path::Path::new("."),
    )
    .unwrap();
    let worst = |strength: f32| {
        let (mesh, mut textures, layout) = strip(1, 256, 1.0);
        let e = emission.map(|c| sdfc::asset::srgb8(c / strength));
        textures.emissive = Some(image::RgbaImage::from_pixel(
            layout.width,
            layout.height,
            image::Rgba([e[0], e[1], e[2], 255]),
        ));
        textures.emissive_strength = strength;
        let r = MeshRenderer::new(&gpu, &mesh, &textures, &layout.into()).unwrap();
        let frame = r.render(&gpu, &v, ViewMode::Color).unwrap();
        let mut worst = 0;
        for y in 0..side {
            for x in 0..side {
                if hit(&v, 1, x, y, 1.0 / 80.0).is_some() {
                    let i = (y * side + x) as usize * 4;
                    for k in 0..3 {
                        worst = worst.max(frame.color[i + k].abs_diff(scene.color[i + k]));
                    }
                }
            }
        }
        worst
    };
    let (carried, clipped) = (worst(1.8), worst(1.0));
    eprintln!("colour off by {carried} bytes with the strength, {clipped} clipped");
    assert!(carried <= 3, "off by {carried} bytes");
    assert!(
        clipped >= 8,
        "clipping made a difference of {clipped} bytes only"
    );
}

/// The standard filter's mip chain (`generic_mips`), against a box filter worked by
/// hand: sizes halve (rounded down, at least 1) down to 1 × 1; a texel is the mean of
/// the 2 × 2 below it, in linear light for sRGB colour (black and white average to
/// 188, sRGB of 0.5) and as stored for alpha and non-colour data; an odd last column
/// repeats.
#[test]
fn the_generic_mip_chain_is_a_box_filter_in_linear_light() {
    let image = image::RgbaImage::from_fn(5, 2, |x, _| {
        let v = if x % 2 == 0 { 0 } else { 255 };
        image::Rgba([v, v, 40 * x as u8, 100])
    });
    let srgb = sdfc::gpu::generic_mips(&image, true);
    let sizes: Vec<_> = srgb.iter().map(|l| l.dimensions()).collect();
    assert_eq!(sizes, [(2, 1), (1, 1)]);
    // Level 1, texel 0: columns 0 and 1 (black, white) → 0.5 linear → 188 encoded.
    let t = srgb[0].get_pixel(0, 0);
    assert_eq!(t[0], sdfc::asset::srgb8(0.5));
    assert_eq!(t[0], 188);
    assert_eq!(t[3], 100, "alpha is averaged as stored");
    // Blue holds 0 and 40 (sRGB-encoded): their mean in linear light.
    let lin = |v: u8| sdfc::ir::texture::srgb_to_linear(v as f64 / 255.0) as f32;
    assert_eq!(t[2], sdfc::asset::srgb8((lin(0) + lin(40)) / 2.0));
    let linear = sdfc::gpu::generic_mips(&image, false);
    let t = linear[0].get_pixel(1, 0);
    // Columns 2 and 3: 0 and 255 → 127.5 → 128; blue 80 and 120 → 100.
    assert_eq!((t[0], t[2]), (128, 100));
    // 1 × 1: the mean of level 1's two texels.
    let top = linear[1].get_pixel(0, 0);
    let below = [linear[0].get_pixel(0, 0)[2], linear[0].get_pixel(1, 0)[2]];
    assert_eq!(
        top[2],
        ((below[0] as f32 + below[1] as f32) / 2.0).round() as u8
    );
    assert!(sdfc::gpu::generic_mips(&image::RgbaImage::new(1, 1), true).is_empty());
}
