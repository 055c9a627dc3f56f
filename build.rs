//! Generates the demo scene's meshes as static fixed-point arrays (`OUT_DIR/demo_meshes.rs`),
//! so firmware and host render identical data without parsing anything at run time.

use std::collections::HashMap;
use std::fmt::Write;

fn normalize(p: [f64; 3]) -> [f64; 3] {
    let l = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
    p.map(|c| c / l)
}

/// Unit icosphere: 12 vertices and 20 faces, each face split in four `subdivisions` times.
fn icosphere(subdivisions: u32) -> (Vec<[f64; 3]>, Vec<[u16; 3]>) {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<[f64; 3]> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .into_iter()
    .map(normalize)
    .collect();
    let mut f: Vec<[u16; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut cache: HashMap<(u16, u16), u16> = HashMap::new();
        let mut next = Vec::with_capacity(f.len() * 4);
        for [a, b, c] in f {
            let mut mid = |x: u16, y: u16| {
                *cache.entry((x.min(y), x.max(y))).or_insert_with(|| {
                    let (p, q) = (v[x as usize], v[y as usize]);
                    v.push(normalize([0, 1, 2].map(|k| (p[k] + q[k]) / 2.0)));
                    (v.len() - 1) as u16
                })
            };
            let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = next;
    }
    (v, f)
}

fn fixed(v: f64) -> i32 {
    (v * 65536.0).round() as i32
}

fn write_vertices(out: &mut String, name: &str, v: &[[f64; 3]]) {
    writeln!(out, "static {name}: [Vertex; {}] = [", v.len()).unwrap();
    for p in v {
        writeln!(
            out,
            "    [c({}), c({}), c({})],",
            fixed(p[0]),
            fixed(p[1]),
            fixed(p[2])
        )
        .unwrap();
    }
    writeln!(out, "];").unwrap();
}

fn write_triangles(out: &mut String, name: &str, f: &[[u16; 3]]) {
    writeln!(out, "static {name}: [[u16; 3]; {}] = [", f.len()).unwrap();
    for t in f {
        writeln!(out, "    [{}, {}, {}],", t[0], t[1], t[2]).unwrap();
    }
    writeln!(out, "];").unwrap();
}

/// A cube of half-size 1, counter-clockwise from outside, two triangles per face.
fn write_cube(out: &mut String) {
    let v: Vec<[f64; 3]> = (0..8)
        .map(|i: usize| {
            let (x, y) = ([-1.0, 1.0, 1.0, -1.0][i % 4], [-1.0, -1.0, 1.0, 1.0][i % 4]);
            [x, y, if i < 4 { -1.0 } else { 1.0 }]
        })
        .collect();
    let f: [[u16; 3]; 12] = [
        [4, 5, 6],
        [4, 6, 7], // +z
        [1, 0, 3],
        [1, 3, 2], // -z
        [5, 1, 2],
        [5, 2, 6], // +x
        [0, 4, 7],
        [0, 7, 3], // -x
        [7, 6, 2],
        [7, 2, 3], // +y
        [0, 1, 5],
        [0, 5, 4], // -y
    ];
    write_vertices(out, "CUBE_VERTICES", &v);
    write_triangles(out, "CUBE_TRIANGLES", &f);
    let faces = [
        "(230, 200, 60)",
        "(60, 170, 220)",
        "(220, 90, 120)",
        "(120, 210, 110)",
        "(240, 240, 235)",
        "(90, 90, 110)",
    ];
    writeln!(out, "static CUBE_COLORS: [Rgb888; 12] = [").unwrap();
    for i in 0..12 {
        writeln!(out, "    Rgb888::new{},", faces[i / 2]).unwrap();
    }
    writeln!(out, "];").unwrap();
}

/// An `n × n` checkerboard in the plane y = 0 spanning ±`half`, facing +y.
fn write_ground(out: &mut String, n: usize, half: f64) {
    let mut v = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let s = |k: usize| -half + 2.0 * half * k as f64 / n as f64;
            v.push([s(i), 0.0, s(j)]);
        }
    }
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u16;
    let mut f = Vec::new();
    let mut colors = Vec::new();
    for j in 0..n {
        for i in 0..n {
            f.push([id(i, j), id(i, j + 1), id(i + 1, j + 1)]);
            f.push([id(i, j), id(i + 1, j + 1), id(i + 1, j)]);
            let c = if (i + j) % 2 == 0 {
                "(200, 200, 190)"
            } else {
                "(70, 80, 90)"
            };
            colors.extend([c, c]);
        }
    }
    write_vertices(out, "GROUND_VERTICES", &v);
    write_triangles(out, "GROUND_TRIANGLES", &f);
    writeln!(out, "static GROUND_COLORS: [Rgb888; {}] = [", colors.len()).unwrap();
    for c in colors {
        writeln!(out, "    Rgb888::new{c},").unwrap();
    }
    writeln!(out, "];").unwrap();
}

/// QEMU `virt` (RV32): 16 MiB of RAM at 0x8000_0000, loaded there with `-bios none -kernel`.
const RISCV_VIRT_MEMORY: &str = "MEMORY\n{\n  RAM : ORIGIN = 0x80000000, LENGTH = 16M\n}\n\
REGION_ALIAS(\"REGION_TEXT\", RAM);\nREGION_ALIAS(\"REGION_RODATA\", RAM);\n\
REGION_ALIAS(\"REGION_DATA\", RAM);\nREGION_ALIAS(\"REGION_BSS\", RAM);\n\
REGION_ALIAS(\"REGION_HEAP\", RAM);\nREGION_ALIAS(\"REGION_STACK\", RAM);\n";

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    // The firmware example links with the runtime's link.x. On Arm, cortex-m-rt's link.x
    // includes memory.x from the linker search path (the top-level one). On RISC-V,
    // `.cargo/config.toml` passes memory-riscv-virt.x (QEMU virt's RAM, with the region
    // aliases riscv-rt places sections through) ahead of link.x.
    let out = std::path::PathBuf::from(std::env::var("OUT_DIR").unwrap());
    if std::env::var("CARGO_CFG_TARGET_ARCH").as_deref() == Ok("riscv32") {
        std::fs::write(out.join("memory-riscv-virt.x"), RISCV_VIRT_MEMORY).unwrap();
    } else {
        std::fs::copy("memory.x", out.join("memory.x")).unwrap();
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=memory.x");
    let (v, f) = icosphere(3);
    let mut out = String::new();
    writeln!(
        out,
        "// Generated by build.rs: unit icosphere, {} vertices, {} triangles.",
        v.len(),
        f.len()
    )
    .unwrap();
    write_vertices(&mut out, "ICOSPHERE_VERTICES", &v);
    // On a unit sphere the vertex normal is the vertex itself.
    writeln!(
        out,
        "// Vertex normals: equal to the positions on a unit sphere."
    )
    .unwrap();
    writeln!(
        out,
        "static ICOSPHERE_NORMALS: [Vertex; {}] = ICOSPHERE_VERTICES;",
        v.len()
    )
    .unwrap();
    write_triangles(&mut out, "ICOSPHERE_TRIANGLES", &f);
    // Per-face colours: a warm-to-cool band by latitude with a faint stripe by longitude.
    writeln!(out, "static ICOSPHERE_COLORS: [Rgb888; {}] = [", f.len()).unwrap();
    for t in &f {
        let c = normalize([0, 1, 2].map(|k| t.iter().map(|&i| v[i as usize][k]).sum::<f64>()));
        let lat = (c[1] + 1.0) / 2.0;
        let stripe = if (c[2].atan2(c[0]) * 6.0 / std::f64::consts::PI).floor() as i64 % 2 == 0 {
            0.0
        } else {
            18.0
        };
        let r = (235.0 - 150.0 * lat + stripe).clamp(0.0, 255.0) as u8;
        let g = (90.0 + 90.0 * lat).clamp(0.0, 255.0) as u8;
        let b = (60.0 + 180.0 * lat - stripe).clamp(0.0, 255.0) as u8;
        writeln!(out, "    Rgb888::new({r}, {g}, {b}),").unwrap();
    }
    writeln!(out, "];").unwrap();
    write_cube(&mut out);
    write_ground(&mut out, 8, 4.0);
    let path = std::path::Path::new(&std::env::var("OUT_DIR").unwrap()).join("demo_meshes.rs");
    std::fs::write(path, out).unwrap();
}
