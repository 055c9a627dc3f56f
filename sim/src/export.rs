//! `sim export`: Rust source for firmware with a scene's data as `static` fixed-point arrays (in
//! flash, no parsing on the target) and the capacities `sim analyze` measured for it.

use crate::analyze::Analysis;
use crate::scene::{f32_literal, CameraSpec, LightSpec, MeshData};
use embedded_graphics::pixelcolor::RgbColor;
use std::fmt::Write;

/// What goes into the generated file.
pub struct Export<'a> {
    /// The mesh (identity transform).
    pub mesh: &'a MeshData,
    /// The analysis the budget comes from.
    pub analysis: &'a Analysis,
    /// The views analysed (exported so firmware can render exactly those).
    pub views: &'a [CameraSpec],
    /// The light.
    pub light: LightSpec,
    /// Back-face culling used in the analysis.
    pub cull_back_faces: bool,
    /// Safety margin on the capacities, percent.
    pub margin_percent: u32,
    /// Also export unit vertex normals: the OBJ file's, else area-weighted ones (only Gouraud
    /// shading reads them).
    pub normals: bool,
    /// The command that produced the file (recorded in its header).
    pub command: String,
    /// A BSP tree built for `mesh` (then `mesh` is the tree's split mesh): exported as
    /// `static` nodes validated at compile time, with the traversal stack it needs.
    pub bsp: Option<&'a crate::bsp::Bsp>,
    /// Light the face colours ahead of time with this set-up arithmetic (`sim export
    /// --bake-light`): the colour table is what `Flat` shading gives each face under `light`
    /// ([`scanline3d::shading::bake_face_colors`]), for drawing with `Unlit` shading.
    pub bake_light: Option<crate::scene::SetupArith>,
}

/// The face colours `Flat` shading gives `mesh` (identity transform) under `light` with the
/// set-up arithmetic `arith`: [`scanline3d::shading::bake_face_colors`].
pub fn baked_colors(
    mesh: &MeshData,
    light: &LightSpec,
    arith: crate::scene::SetupArith,
) -> Result<Vec<embedded_graphics::pixelcolor::Rgb888>, String> {
    use crate::scene::SetupArith as S;
    use scanline3d::arithmetic::{Frugal, Precise, Quick};
    use scanline3d::scene::Transform;
    use scanline3d::shading::bake_face_colors;
    let m = mesh.mesh()?;
    let light = light.fixed()?;
    let mut out = vec![embedded_graphics::pixelcolor::Rgb888::BLACK; mesh.triangles.len()];
    let t = Transform::IDENTITY;
    match arith {
        S::Precise | S::NarrowTransform | S::Reciprocal => {
            bake_face_colors::<Precise>(&m, &t, &light, &mut out)
        }
        S::Quick => bake_face_colors::<Quick>(&m, &t, &light, &mut out),
        S::Frugal | S::NarrowNormals => bake_face_colors::<Frugal>(&m, &t, &light, &mut out),
    }
    .map_err(|e| e.to_string())?;
    Ok(out)
}

/// The mesh's own vertex normals (from the OBJ file) in I16F16 bits when it has them, else
/// area-weighted vertex normals, unit length, rounded to I16F16 bits.
fn vertex_normals(mesh: &MeshData) -> Vec<[i32; 3]> {
    if let Some(n) = &mesh.normals {
        return n.iter().map(|v| v.map(|c| c.to_bits())).collect();
    }
    let p = |i: u16| mesh.vertices[i as usize].map(|c| c.to_num::<f64>());
    let mut acc = vec![[0.0f64; 3]; mesh.vertices.len()];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(p);
        let (u, v) = (
            [0, 1, 2].map(|k| b[k] - a[k]),
            [0, 1, 2].map(|k| c[k] - a[k]),
        );
        let n = crate::reference::cross(u, v);
        for &i in t {
            for k in 0..3 {
                acc[i as usize][k] += n[k];
            }
        }
    }
    acc.iter()
        .map(|n| {
            crate::reference::normalize(*n)
                .unwrap_or([0.0, 0.0, 1.0])
                .map(|c| (c * 65536.0).round() as i32)
        })
        .collect()
}

fn vec3(v: [f64; 3]) -> String {
    format!(
        "[{}, {}, {}]",
        f32_literal(v[0]),
        f32_literal(v[1]),
        f32_literal(v[2])
    )
}

/// A tuple expression, one item per line (`rustfmt` joins short ones).
fn tuple(items: &[String], indent: usize) -> String {
    let pad = " ".repeat(indent + 4);
    let mut s = "(\n".to_string();
    for item in items {
        s += &format!("{pad}{item},\n");
    }
    s + &" ".repeat(indent) + ")"
}

/// Formats Rust source with `rustfmt` (edition 2021), as bindgen does; `None` if rustfmt is
/// not installed or fails.
pub fn rustfmt(source: &str) -> Option<String> {
    use std::io::Write as _;
    use std::process::{Command, Stdio};
    let mut child = Command::new("rustfmt")
        .args(["--edition", "2021", "--emit", "stdout", "--quiet"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .ok()?;
    child.stdin.take()?.write_all(source.as_bytes()).ok()?;
    let out = child.wait_with_output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8(out.stdout).ok())
        .flatten()
}

/// The tree as `static` nodes (pre-order), the map back to the input triangles and the
/// traversal stack.
fn bsp_source(b: &crate::bsp::Bsp) -> String {
    let mut s = String::new();
    let child = |c: u16| {
        if c == scanline3d::resolve::bsp::NO_CHILD {
            "NO_CHILD".to_string()
        } else {
            c.to_string()
        }
    };
    let _ = writeln!(
        s,
        "/// BSP nodes in pre-order: {} nodes, depth {}; input triangles cut by planes: {}.",
        b.nodes.len(),
        b.depth,
        b.splits
    );
    let _ = writeln!(s, "pub static BSP_NODES: [BspNode; {}] = [", b.nodes.len());
    for n in &b.nodes {
        let plane = n.plane.map(|v| f32_literal(v as f64));
        let _ = writeln!(
            s,
            "    BspNode {{ plane: [{}], front: {}, back: {}, first: {}, count: {}, facing_front: {} }},",
            plane.join(", "),
            child(n.front),
            child(n.back),
            n.first,
            n.count,
            n.facing_front
        );
    }
    s += "];\n\n";
    let _ = writeln!(
        s,
        "/// For each triangle, the input (OBJ) triangle it is, or is a piece of."
    );
    let _ = writeln!(s, "pub static ORIGIN: [u32; {}] = [", b.origin.len());
    for chunk in b.origin.chunks(16) {
        let items: Vec<String> = chunk.iter().map(|o| o.to_string()).collect();
        let _ = writeln!(s, "    {},", items.join(", "));
    }
    s += "];\n\n";
    s += "/// The tree, validated at compile time.\n";
    s += "pub static BSP_TREE: BspTree<'static> = valid_tree(BspTree::new(&BSP_NODES, TRIANGLES.len()));\n\n";
    let _ = writeln!(
        s,
        "/// Traversal stack the tree needs: two entries per level plus one."
    );
    let _ = writeln!(s, "pub const BSP_STACK: usize = {};\n", b.stack_needed());
    s
}

impl Export<'_> {
    /// The generated source, laid out close to rustfmt's style (pass it through [`rustfmt`]).
    pub fn source(&self) -> Result<String, String> {
        let baked;
        let m = match self.bake_light {
            Some(arith) => {
                if self.normals {
                    return Err("--bake-light exports colours for Unlit shading: no normals (Gouraud would light them again)".into());
                }
                baked = MeshData {
                    colors: baked_colors(self.mesh, &self.light, arith)?,
                    ..self.mesh.clone()
                };
                &baked
            }
            None => self.mesh,
        };
        let a = self.analysis;
        let (nv, nt) = (m.vertices.len(), m.triangles.len());
        let tris = a.triangle_capacity(self.margin_percent);
        let active = a.active_capacity(self.margin_percent);
        let uniform = m.colors.windows(2).all(|w| w[0] == w[1]);
        let mut s = String::new();
        let _ = writeln!(s, "//! Generated by `{}`: do not edit.", self.command);
        let _ = writeln!(s, "//!");
        let _ = writeln!(
            s,
            "//! {nv} vertices and {nt} triangles as I16F16 `static` arrays, and the budget `sim analyze`"
        );
        let _ = writeln!(
            s,
            "//! measured over {} view(s) at {}x{} with a {} % margin.",
            a.views, a.width, a.height, self.margin_percent
        );
        if let Some(b) = self.bsp {
            let _ = writeln!(
                s,
                "//! The mesh is the split mesh of a BSP tree built for the OBJ's {} triangles (`BSP_TREE`).",
                b.origin.iter().max().map_or(0, |&o| o as usize + 1)
            );
        }
        if let Some(arith) = self.bake_light {
            let _ = writeln!(
                s,
                "//!\n//! The face colours are lit ahead of time (`scanline3d::shading::bake_face_colors`, {} arithmetic)\n//! for `LIGHT` and the mesh where it is (identity transform): draw it with `scanline3d::Unlit`\n//! shading, which gives the pixels `Flat` gives the original colours, while the light and the\n//! mesh stay put (the camera may move).",
                arith.name()
            );
        }
        let _ = writeln!(
            s,
            "//!\n//! Include it as a module (`mod scene;`); the firmware crate needs `scanline3d`, `fixed` and\n//! `embedded-graphics` as dependencies. Render with `SceneStorage<YourConfig>`."
        );
        s += "#![allow(dead_code)] // a firmware uses what its views need of this file\n\n";
        let mut uses = vec!["embedded_graphics::pixelcolor::Rgb888"];
        uses.push("fixed::types::I16F16");
        uses.push("scanline3d::scene::{Mesh, MeshColors, SceneError, Vertex}");
        // Up to 255 filed triangles, one-byte bucket heads halve the heads' RAM.
        let byte_heads = tris <= u8::MAX as usize;
        uses.push(if byte_heads {
            "scanline3d::{Depth, Storage, Workspace}"
        } else {
            "scanline3d::{Storage, Workspace}"
        });
        if self.bsp.is_some() {
            uses.push("scanline3d::resolve::bsp::{BspNode, BspTree, BspWorkspace, NO_CHILD}");
        }
        for u in uses {
            let _ = writeln!(s, "use {u};");
        }
        s += "\nconst fn c(bits: i32) -> I16F16 {\n    I16F16::from_bits(bits)\n}\n\n";
        s += "const fn valid(mesh: Result<Mesh<'static>, SceneError>) -> Mesh<'static> {\n";
        s += "    match mesh {\n        Ok(mesh) => mesh,\n";
        s += "        // Evaluated at compile time: invalid data fails the build.\n";
        s += "        Err(_) => panic!(\"invalid mesh\"),\n    }\n}\n\n";
        if self.bsp.is_some() {
            s += "const fn valid_tree(tree: Result<BspTree<'static>, scanline3d::resolve::bsp::BspError>) -> BspTree<'static> {\n";
            s += "    match tree {\n        Ok(tree) => tree,\n";
            s += "        // Evaluated at compile time: an invalid tree fails the build.\n";
            s += "        Err(_) => panic!(\"invalid BSP tree\"),\n    }\n}\n\n";
        }
        let _ = writeln!(s, "/// Model-space positions (I16F16 bits).");
        let _ = writeln!(s, "pub static VERTICES: [Vertex; {nv}] = [");
        for v in &m.vertices {
            let b = v.map(|c| c.to_bits());
            let _ = writeln!(s, "    [c({}), c({}), c({})],", b[0], b[1], b[2]);
        }
        s += "];\n\n";
        let _ = writeln!(s, "/// Triangles, counter-clockwise seen from the front.");
        let _ = writeln!(s, "pub static TRIANGLES: [[u16; 3]; {nt}] = [");
        for t in &m.triangles {
            let _ = writeln!(s, "    [{}, {}, {}],", t[0], t[1], t[2]);
        }
        s += "];\n\n";
        let colors = if uniform {
            let c = m.colors.first().copied().unwrap_or_default();
            format!(
                "MeshColors::Uniform(Rgb888::new({}, {}, {}))",
                c.r(),
                c.g(),
                c.b()
            )
        } else {
            let _ = writeln!(
                s,
                "{}",
                if self.bake_light.is_some() {
                    "/// One colour per triangle, lit for `LIGHT` (draw with `Unlit` shading)."
                } else {
                    "/// One colour per triangle."
                }
            );
            let _ = writeln!(s, "pub static FACE_COLORS: [Rgb888; {nt}] = [");
            for c in &m.colors {
                let _ = writeln!(s, "    Rgb888::new({}, {}, {}),", c.r(), c.g(), c.b());
            }
            s += "];\n\n";
            "MeshColors::PerFace(&FACE_COLORS)".to_string()
        };
        let normals = if self.normals {
            let _ = writeln!(
                s,
                "/// Unit vertex normals (I16F16 bits), for Gouraud shading."
            );
            let _ = writeln!(s, "pub static VERTEX_NORMALS: [Vertex; {nv}] = [");
            for n in vertex_normals(m) {
                let _ = writeln!(s, "    [c({}), c({}), c({})],", n[0], n[1], n[2]);
            }
            s += "];\n\n";
            "Some(&VERTEX_NORMALS)"
        } else {
            "None"
        };
        let _ = writeln!(s, "/// The mesh's colours.");
        let _ = writeln!(s, "const COLORS: MeshColors<'static> = {colors};");
        let _ = writeln!(s, "/// Vertex normals, if exported.");
        let _ = writeln!(s, "const NORMALS: Option<&[Vertex]> = {normals};\n");
        s += "/// The mesh, validated at compile time.\n";
        s += "pub static MESH: Mesh<'static> = valid(Mesh::new(&VERTICES, &TRIANGLES, COLORS, NORMALS));\n\n";
        if let Some(b) = self.bsp {
            s += &bsp_source(b);
        }
        let _ = writeln!(s, "/// Target width the budget was measured for.");
        let _ = writeln!(s, "pub const WIDTH: usize = {};", a.width);
        let _ = writeln!(s, "/// Target height the budget was measured for.");
        let _ = writeln!(s, "pub const HEIGHT: usize = {};", a.height);
        let _ = writeln!(
            s,
            "/// Triangles filed per frame: {} measured, plus the margin.",
            a.max_bucketed
        );
        let _ = writeln!(s, "pub const MAX_TRIANGLES: usize = {tris};");
        let _ = writeln!(
            s,
            "/// Triangles crossing one row: {} measured, plus the margin.",
            a.peak_active
        );
        let _ = writeln!(s, "pub const MAX_ACTIVE: usize = {active};");
        match &a.newell_error {
            None => {
                let _ = writeln!(
                    s,
                    "/// Newell's depth sort (`PIECES`): {} workspace entries and {} sort steps measured, plus the margin.",
                    a.newell.entries, a.newell.steps
                );
                let _ = writeln!(
                    s,
                    "pub const NEWELL_PIECES: usize = {};",
                    a.newell.pieces_capacity(self.margin_percent)
                );
            }
            Some(e) => {
                let _ = writeln!(s, "// Newell's depth sort was not measured: {e}");
            }
        }
        let _ = writeln!(
            s,
            "/// Whether any analysed view needed clipping (if not, `NoClip` is safe for these views)."
        );
        let _ = writeln!(
            s,
            "pub const NEEDS_CLIPPING: bool = {};",
            a.views_clipping > 0
        );
        let _ = writeln!(s, "/// Back-face culling, as analysed.");
        let _ = writeln!(
            s,
            "pub const CULL_BACK_FACES: bool = {};",
            self.cull_back_faces
        );
        let _ = writeln!(s, "/// Mesh instances: this file holds one mesh.");
        let _ = writeln!(s, "pub const INSTANCES: usize = 1;");
        if byte_heads {
            let _ = writeln!(
                s,
                "/// The workspace this budget asks for, with one-byte row bucket heads (`MAX_TRIANGLES` <= 255)."
            );
            s += "pub type SceneWorkspace<P, S> =\n    Workspace<P, S, WIDTH, HEIGHT, MAX_TRIANGLES, MAX_ACTIVE, INSTANCES, Depth, 0, u8>;\n";
        } else {
            let _ = writeln!(s, "/// The workspace this budget asks for.");
            s += "pub type SceneWorkspace<P, S> =\n    Workspace<P, S, WIDTH, HEIGHT, MAX_TRIANGLES, MAX_ACTIVE, INSTANCES>;\n";
        }
        s += "/// The renderer this budget asks for, for configuration `C` (a `scanline3d::Config`).\n";
        s += "pub type SceneStorage<C> = Storage<C, WIDTH, HEIGHT, MAX_TRIANGLES, MAX_ACTIVE>;\n\n";
        if self.bsp.is_some() {
            let _ = writeln!(
                s,
                "/// The BSP workspace this budget and tree ask for (painter's order from `BSP_TREE`)."
            );
            s += "pub type SceneBspWorkspace<P, S> =\n    BspWorkspace<P, S, WIDTH, HEIGHT, MAX_TRIANGLES, MAX_ACTIVE, BSP_STACK>;\n\n";
        }
        let first = self
            .views
            .first()
            .copied()
            .unwrap_or(CameraSpec::looking_at(
                [0.0, 0.0, 1.0],
                [0.0; 3],
                50.0,
                0.1,
                100.0,
            ));
        let _ = writeln!(
            s,
            "/// Vertical field of view (degrees), near and far planes of every view."
        );
        let _ = writeln!(
            s,
            "pub const PROJECTION: (f32, f32, f32) = {};",
            tuple(&[first.fovy, first.near, first.far].map(f32_literal), 0)
        );
        let _ = writeln!(s, "/// The analysed views: eye, target, up.");
        let _ = writeln!(
            s,
            "pub const VIEWS: [([f32; 3], [f32; 3], [f32; 3]); {}] = [",
            self.views.len()
        );
        for v in self.views {
            let _ = writeln!(s, "    {},", tuple(&[v.eye, v.target, v.up].map(vec3), 4));
        }
        s += "];\n\n";
        let l = self.light;
        let _ = writeln!(
            s,
            "{}",
            if self.bake_light.is_some() {
                "/// The light: towards the light, ambient, diffuse (the face colours are lit for it)."
            } else {
                "/// The light: towards the light, ambient, diffuse."
            }
        );
        let _ = writeln!(
            s,
            "pub const LIGHT: ([f32; 3], f32, f32) = {};",
            tuple(
                &[
                    vec3(l.direction),
                    f32_literal(l.ambient),
                    f32_literal(l.diffuse)
                ],
                0
            )
        );
        Ok(s)
    }
}

/// Every corpus scene ([`crate::corpus::all`]) as one Rust file for firmware: a module per
/// scene ([`Export::source`] of its mesh, views, light and budget at `w × h`), then `SCENES`
/// listing them and `MAX_TRIANGLES` / `MAX_ACTIVE` / `MAX_VERTICES` covering all. `cargo xtask tradeoff`
/// writes it under `target/` and builds `firmware/examples/tradeoff.rs` with it
/// (`--cfg scanline3d_corpus`, path in `SCANLINE3D_CORPUS`) to count instructions per corpus
/// scene on the targets.
pub fn corpus_source(w: usize, h: usize, margin_percent: u32) -> Result<String, String> {
    let mut s = String::new();
    s +=
        "// Generated by `cargo xtask tradeoff` (`scanline3d_sim::export::corpus_source`): every\n";
    s += "// corpus scene as `static` data for the trade-off firmware. Not committed; do not edit.\n\n";
    let mut entries = Vec::new();
    let (mut tris, mut active, mut vertices) = (0usize, 0usize, 0usize);
    for scene in crate::corpus::all() {
        let spec = crate::scene::SceneSpec::single(
            scene.mesh.clone(),
            scene.cameras[0],
            LightSpec::default(),
            scene.cull_back_faces,
        );
        let analysis = crate::analyze::analyze(&spec, &scene.cameras, w, h)?;
        tris = tris.max(analysis.triangle_capacity(margin_percent));
        vertices = vertices.max(scene.mesh.vertices.len());
        active = active.max(analysis.active_capacity(margin_percent));
        let export = Export {
            mesh: &scene.mesh,
            analysis: &analysis,
            views: &scene.cameras,
            light: LightSpec::default(),
            cull_back_faces: scene.cull_back_faces,
            margin_percent,
            normals: false,
            command: format!("scanline3d_sim::export::corpus_source({w}, {h}, {margin_percent})"),
            bsp: None,
            bake_light: None,
        };
        let module = scene.name.replace('-', "_");
        let _ = writeln!(s, "#[allow(dead_code)]\npub mod {module} {{");
        s += &export.source()?;
        // The same faces lit ahead of time, for `Unlit` shading (`cargo xtask profile baked`;
        // only that build's `SCENES` refer to them, so no other build links them).
        let baked = baked_colors(
            &scene.mesh,
            &LightSpec::default(),
            crate::scene::SetupArith::Precise,
        )?;
        let _ = writeln!(s, "/// The face colours lit for `LIGHT` (default arithmetic), for `Unlit` shading.\npub static BAKED_COLORS: [Rgb888; {}] = [", baked.len());
        for c in &baked {
            let _ = writeln!(s, "    Rgb888::new({}, {}, {}),", c.r(), c.g(), c.b());
        }
        s += "];\n/// `MESH` with the baked colours.\npub static BAKED_MESH: Mesh<'static> = valid(Mesh::new(&VERTICES, &TRIANGLES, MeshColors::PerFace(&BAKED_COLORS), None));\n";
        // Views may differ in projection; `PROJECTION` above is the first view's.
        let _ = writeln!(
            s,
            "/// Vertical field of view (degrees), near and far plane of each view.\npub const PROJECTIONS: [(f32, f32, f32); {}] = [",
            scene.cameras.len()
        );
        for c in &scene.cameras {
            let _ = writeln!(
                s,
                "    {},",
                tuple(&[c.fovy, c.near, c.far].map(f32_literal), 4)
            );
        }
        s += "];\n}\n\n";
        entries.push((scene.name, module));
    }
    s += "/// One corpus scene as the firmware renders it.\n";
    s += "pub struct CorpusScene {\n    pub name: &'static str,\n    pub mesh: &'static scanline3d::scene::Mesh<'static>,\n    #[cfg(scanline3d_variant = \"baked\")]\n    pub baked: &'static scanline3d::scene::Mesh<'static>,\n    pub cull_back_faces: bool,\n    pub projections: &'static [(f32, f32, f32)],\n    pub views: &'static [([f32; 3], [f32; 3], [f32; 3])],\n    pub light: ([f32; 3], f32, f32),\n}\n\n";
    let _ = writeln!(s, "pub static SCENES: [CorpusScene; {}] = [", entries.len());
    for (name, m) in &entries {
        let _ = writeln!(
            s,
            "    CorpusScene {{ name: {name:?}, mesh: &{m}::MESH, #[cfg(scanline3d_variant = \"baked\")] baked: &{m}::BAKED_MESH, cull_back_faces: {m}::CULL_BACK_FACES, projections: &{m}::PROJECTIONS, views: &{m}::VIEWS, light: {m}::LIGHT }},"
        );
    }
    s += "];\n\n";
    let _ = writeln!(
        s,
        "/// Triangles filed per frame, the largest over all scenes (with the margin).\npub const MAX_TRIANGLES: usize = {tris};"
    );
    let _ = writeln!(
        s,
        "/// Triangles crossing one row, the largest over all scenes (with the margin).\npub const MAX_ACTIVE: usize = {active};"
    );
    let _ = writeln!(
        s,
        "/// Vertices of the largest mesh (a vertex cache holding every vertex).\npub const MAX_VERTICES: usize = {vertices};"
    );
    Ok(s)
}
