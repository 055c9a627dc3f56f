//! The float reference: f64 ray casting through pixel centres.
//!
//! Independent of the fixed-point renderer: it shares the scene description (vertex positions,
//! colours, light, camera parameters) and the conventions (camera looks down −z, `gluLookAt` /
//! `gluPerspective`, pixel centres at (c + ½, r + ½), eye depth along the view axis), but none of
//! the arithmetic. Triangles use Möller–Trumbore behind a bounding-volume hierarchy; spheres and
//! planes are there for analytic scenes.

/// A 3-vector.
pub type V3 = [f64; 3];

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
/// Cross product.
pub fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
/// Dot product.
pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
/// Unit vector, or `None` for a zero or non-finite vector.
pub fn normalize(a: V3) -> Option<V3> {
    let l = dot(a, a).sqrt();
    (l > 0.0 && l.is_finite()).then(|| scale(a, 1.0 / l))
}

/// A perspective camera in f64 (`gluLookAt` + `gluPerspective`).
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    /// Eye position.
    pub eye: V3,
    forward: V3,
    side: V3,
    up: V3,
    tan_half: f64,
    /// Near-plane eye depth.
    pub near: f64,
    /// Far-plane eye depth.
    pub far: f64,
}

impl Camera {
    /// `None` for a degenerate camera (eye == target, up parallel to the view, bad angles).
    pub fn new(
        eye: V3,
        target: V3,
        up: V3,
        fovy_degrees: f64,
        near: f64,
        far: f64,
    ) -> Option<Self> {
        let forward = normalize(sub(target, eye))?;
        let side = normalize(cross(forward, up))?;
        let up = cross(side, forward);
        if !(fovy_degrees > 0.0 && fovy_degrees < 180.0 && near > 0.0 && near < far) {
            return None;
        }
        Some(Camera {
            eye,
            forward,
            side,
            up,
            tan_half: (fovy_degrees.to_radians() / 2.0).tan(),
            near,
            far,
        })
    }

    /// Direction of the ray through screen point `(x, y)` (pixels) of a `w × h` image, scaled so
    /// its component along the view axis is 1 (the ray parameter is then the eye depth).
    pub fn ray(&self, x: f64, y: f64, w: usize, h: usize) -> V3 {
        let aspect = w as f64 / h as f64;
        let sx = (x / w as f64 * 2.0 - 1.0) * self.tan_half * aspect;
        let sy = (1.0 - y / h as f64 * 2.0) * self.tan_half;
        add(self.forward, add(scale(self.side, sx), scale(self.up, sy)))
    }

    /// Eye-space coordinates of a world point: (right, up, depth along the view axis).
    pub fn eye_coords(&self, p: V3) -> V3 {
        let d = sub(p, self.eye);
        [dot(d, self.side), dot(d, self.up), dot(d, self.forward)]
    }

    /// Eye depth of a world point (distance along the view axis).
    pub fn depth(&self, p: V3) -> f64 {
        dot(sub(p, self.eye), self.forward)
    }

    /// Screen position in pixels of a world point in front of the eye (`None` behind it).
    pub fn project(&self, p: V3, w: usize, h: usize) -> Option<[f64; 2]> {
        let d = sub(p, self.eye);
        let z = dot(d, self.forward);
        if z <= 0.0 {
            return None;
        }
        let aspect = w as f64 / h as f64;
        let x = dot(d, self.side) / z / (self.tan_half * aspect);
        let y = dot(d, self.up) / z / self.tan_half;
        Some([(x + 1.0) / 2.0 * w as f64, (1.0 - y) / 2.0 * h as f64])
    }

    /// Pixels per world unit at eye depth 1 (vertically).
    pub fn focal_px(&self, h: usize) -> f64 {
        h as f64 / 2.0 / self.tan_half
    }
}

/// A directional light with ambient term (the renderer's lighting model).
#[derive(Clone, Copy, Debug)]
pub struct Light {
    /// Unit vector towards the light.
    pub direction: V3,
    /// Ambient intensity.
    pub ambient: f64,
    /// Diffuse intensity.
    pub diffuse: f64,
}

impl Light {
    /// Intensity for unit normal `n`: `ambient + diffuse · max(0, n · l)`, clamped to 1.
    pub fn intensity(&self, n: V3) -> f64 {
        (self.ambient + self.diffuse * dot(n, self.direction).max(0.0)).clamp(0.0, 1.0)
    }
}

/// A world-space triangle with its base colour (0–255 per channel).
#[derive(Clone, Copy, Debug)]
pub struct Triangle {
    /// Vertices, counter-clockwise seen from the front.
    pub v: [V3; 3],
    /// Base colour.
    pub color: [f64; 3],
}

/// An analytic sphere.
#[derive(Clone, Copy, Debug)]
pub struct Sphere {
    /// Centre.
    pub centre: V3,
    /// Radius.
    pub radius: f64,
    /// Base colour.
    pub color: [f64; 3],
}

/// An analytic plane `n · p = d`, one-sided (its front faces along `n`).
#[derive(Clone, Copy, Debug)]
pub struct Plane {
    /// Unit normal.
    pub normal: V3,
    /// Offset.
    pub d: f64,
    /// Base colour.
    pub color: [f64; 3],
}

/// What a ray hit: object id (triangles first, then spheres, then planes), eye depth, colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Object id.
    pub id: i32,
    /// Eye depth along the view axis.
    pub depth: f64,
    /// Shaded colour (flat: base × Lambert + ambient with the geometric normal).
    pub color: [u8; 3],
}

#[derive(Clone, Copy, Debug)]
struct Aabb {
    lo: V3,
    hi: V3,
}

impl Aabb {
    const EMPTY: Aabb = Aabb {
        lo: [f64::INFINITY; 3],
        hi: [f64::NEG_INFINITY; 3],
    };
    fn grow(&mut self, p: V3) {
        self.lo = [0, 1, 2].map(|k| self.lo[k].min(p[k]));
        self.hi = [0, 1, 2].map(|k| self.hi[k].max(p[k]));
    }
    /// Slab test: whether the ray enters the box before `t_max`.
    fn hit(&self, origin: V3, inv: V3, t_max: f64) -> bool {
        let (mut t0, mut t1) = (0.0f64, t_max);
        for k in 0..3 {
            let a = (self.lo[k] - origin[k]) * inv[k];
            let b = (self.hi[k] - origin[k]) * inv[k];
            let (a, b) = if a <= b { (a, b) } else { (b, a) };
            // NaN (0 · inf) means the ray lies in the slab's plane: treat as inside.
            if a.is_finite() || a == f64::NEG_INFINITY {
                t0 = t0.max(a);
            }
            if b.is_finite() || b == f64::INFINITY {
                t1 = t1.min(b);
            }
            if t0 > t1 {
                return false;
            }
        }
        true
    }
}

#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Aabb,
    /// Leaf: `first..first + count` in `order`; inner: children at `first` and `first + 1`.
    first: u32,
    count: u32,
}

/// A bounding-volume hierarchy over triangles (median split on the widest centroid axis).
#[derive(Clone, Debug, Default)]
struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
}

const LEAF_SIZE: usize = 4;

impl Bvh {
    fn build(tris: &[Triangle]) -> Bvh {
        let mut bvh = Bvh {
            nodes: Vec::new(),
            order: (0..tris.len() as u32).collect(),
        };
        if tris.is_empty() {
            return bvh;
        }
        let centroid = |i: u32| {
            scale(
                add(
                    add(tris[i as usize].v[0], tris[i as usize].v[1]),
                    tris[i as usize].v[2],
                ),
                1.0 / 3.0,
            )
        };
        bvh.nodes.push(Node {
            bounds: Aabb::EMPTY,
            first: 0,
            count: tris.len() as u32,
        });
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            let (first, count) = (bvh.nodes[n].first as usize, bvh.nodes[n].count as usize);
            let mut bounds = Aabb::EMPTY;
            let mut cb = Aabb::EMPTY;
            for &i in &bvh.order[first..first + count] {
                for p in tris[i as usize].v {
                    bounds.grow(p);
                }
                cb.grow(centroid(i));
            }
            bvh.nodes[n].bounds = bounds;
            if count <= LEAF_SIZE {
                continue;
            }
            let axis = (0..3)
                .max_by(|&a, &b| (cb.hi[a] - cb.lo[a]).total_cmp(&(cb.hi[b] - cb.lo[b])))
                .unwrap_or(0);
            let slice = &mut bvh.order[first..first + count];
            slice.sort_by(|&a, &b| centroid(a)[axis].total_cmp(&centroid(b)[axis]));
            let half = count / 2;
            let left = bvh.nodes.len();
            bvh.nodes.push(Node {
                bounds: Aabb::EMPTY,
                first: first as u32,
                count: half as u32,
            });
            bvh.nodes.push(Node {
                bounds: Aabb::EMPTY,
                first: (first + half) as u32,
                count: (count - half) as u32,
            });
            bvh.nodes[n].first = left as u32;
            bvh.nodes[n].count = 0;
            stack.push(left);
            stack.push(left + 1);
        }
        bvh
    }
}

/// A scene for the reference: world-space primitives, light, camera, culling.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Triangles (ids 0..).
    pub triangles: Vec<Triangle>,
    /// Spheres (ids after the triangles).
    pub spheres: Vec<Sphere>,
    /// Planes (ids after the spheres).
    pub planes: Vec<Plane>,
    /// The light.
    pub light: Light,
    /// The camera.
    pub camera: Camera,
    /// Skip triangles whose back faces the ray.
    pub cull_back_faces: bool,
    /// Per triangle, the base colours of its three vertices (Gouraud); empty: flat, each
    /// triangle's `color`.
    pub vertex_colors: Vec<[[f64; 3]; 3]>,
    bvh: Bvh,
}

/// A rendered image: ids (−1 = background), eye depth (+inf = background), colour.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// Object ids, row-major from the top.
    pub ids: Vec<i32>,
    /// Eye depth.
    pub depth: Vec<f32>,
    /// Colour.
    pub color: Vec<[u8; 3]>,
}

impl Image {
    /// A `width × height` image of background: no id, infinite depth, black.
    pub fn background(width: usize, height: usize) -> Image {
        Image {
            width,
            height,
            ids: vec![-1; width * height],
            depth: vec![f32::INFINITY; width * height],
            color: vec![[0; 3]; width * height],
        }
    }
}

impl Scene {
    /// A scene over the given primitives; builds the BVH.
    pub fn new(
        triangles: Vec<Triangle>,
        light: Light,
        camera: Camera,
        cull_back_faces: bool,
    ) -> Scene {
        let bvh = Bvh::build(&triangles);
        Scene {
            triangles,
            spheres: Vec::new(),
            planes: Vec::new(),
            light,
            camera,
            cull_back_faces,
            vertex_colors: Vec::new(),
            bvh,
        }
    }

    /// The same scene Gouraud-shaded: triangle `i`'s colour at a point is its vertex colours
    /// `colors[i]` blended by the point's barycentric coordinates on the triangle in space, then
    /// lit with the face normal. Blending in space is what perspective-correct interpolation
    /// approximates on screen; since the light is the same at the three vertices, this equals
    /// blending the lit vertex colours.
    pub fn with_vertex_colors(self, colors: Vec<[[f64; 3]; 3]>) -> Result<Scene, String> {
        if colors.len() != self.triangles.len() {
            return Err(format!(
                "{} vertex colour triples for {} triangles",
                colors.len(),
                self.triangles.len()
            ));
        }
        Ok(Scene {
            vertex_colors: colors,
            ..self
        })
    }

    fn shade(&self, base: [f64; 3], normal: V3) -> [u8; 3] {
        let i = self.light.intensity(normal);
        base.map(|c| (c * i).round().clamp(0.0, 255.0) as u8)
    }

    /// Nearest hit of triangle `i` along `dir` from the eye within [near, far] (eye depth).
    ///
    /// A ray through an edge (a barycentric coordinate within 1e-9 of zero, which in practice
    /// means exactly on it) belongs to the triangle only if that edge is a top or left edge of
    /// its projection on the `w × h` screen: the same fill convention as the renderer, so two
    /// triangles sharing an edge never both claim a centre on it.
    pub fn hit_triangle_on(&self, i: usize, dir: V3, w: usize, h: usize) -> Option<f64> {
        const TIE: f64 = 1e-9;
        let depth = self.hit_triangle(i, dir)?;
        let t = self.triangles.get(i)?;
        let e1 = sub(t.v[1], t.v[0]);
        let e2 = sub(t.v[2], t.v[0]);
        let p = cross(dir, e2);
        let det = dot(e1, p);
        let s = sub(self.camera.eye, t.v[0]);
        let u = dot(s, p) / det;
        let v = dot(dir, cross(s, e1)) / det;
        let bary = [1.0 - u - v, u, v];
        if bary.iter().all(|&b| b > TIE) {
            return Some(depth);
        }
        // On an edge: the edge opposite vertex k is (k+1, k+2).
        let Some(sv) =
            t.v.iter()
                .map(|&p| self.camera.project(p, w, h))
                .collect::<Option<Vec<_>>>()
        else {
            return Some(depth); // a vertex behind the eye: no screen orientation to apply
        };
        let area = (sv[1][0] - sv[0][0]) * (sv[2][1] - sv[0][1])
            - (sv[2][0] - sv[0][0]) * (sv[1][1] - sv[0][1]);
        for k in 0..3 {
            if bary[k] > TIE {
                continue;
            }
            let (mut a, mut b) = (sv[(k + 1) % 3], sv[(k + 2) % 3]);
            if area < 0.0 {
                std::mem::swap(&mut a, &mut b);
            }
            // With positive area in y-down coordinates the interior is to the right of a→b: a
            // top edge runs rightwards horizontally, a left edge runs upwards.
            let top = (a[1] - b[1]).abs() <= TIE * (1.0 + a[1].abs()) && b[0] > a[0];
            let left = b[1] < a[1] - TIE * (1.0 + a[1].abs());
            if !(top || left) {
                return None;
            }
        }
        Some(depth)
    }

    /// Nearest hit of triangle `i` along `dir` from the eye within [near, far] (eye depth),
    /// edges inclusive.
    pub fn hit_triangle(&self, i: usize, dir: V3) -> Option<f64> {
        let t = self.triangles.get(i)?;
        let e1 = sub(t.v[1], t.v[0]);
        let e2 = sub(t.v[2], t.v[0]);
        if self.cull_back_faces && dot(cross(e1, e2), dir) >= 0.0 {
            return None;
        }
        let p = cross(dir, e2);
        let det = dot(e1, p);
        if det == 0.0 {
            return None;
        }
        let s = sub(self.camera.eye, t.v[0]);
        let u = dot(s, p) / det;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = cross(s, e1);
        let v = dot(dir, q) / det;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let depth = dot(e2, q) / det;
        (depth >= self.camera.near && depth <= self.camera.far).then_some(depth)
    }

    /// Whether a hit `(d, id)` beats `(bd, bid)`. Depths equal to 1e-9 (relative) are a tie
    /// between coplanar surfaces, resolved by the renderer's documented convention: the triangle
    /// whose visible part starts on an earlier pixel row wins, then the lower id.
    fn nearer(&self, d: f64, id: i32, bd: f64, bid: i32, w: usize, h: usize) -> bool {
        if (d - bd).abs() > 1e-9 * bd {
            return d < bd;
        }
        let key = |t: i32| (self.first_row(t as usize, w, h), t);
        key(id) < key(bid)
    }

    /// First pixel row whose centre is at or below the top of triangle `t`'s visible projection.
    pub fn first_row(&self, t: usize, w: usize, h: usize) -> i64 {
        let top = self
            .screen_polygon(t, w, h)
            .iter()
            .map(|p| p[1])
            .fold(f64::INFINITY, f64::min);
        (top - 0.5).ceil().max(0.0) as i64
    }

    /// The visible part of triangle `t` on a `w × h` screen: the triangle clipped to the near
    /// and far planes in exact f64 geometry, projected.
    pub fn screen_polygon(&self, t: usize, w: usize, h: usize) -> Vec<[f64; 2]> {
        let cam = &self.camera;
        let Some(tri) = self.triangles.get(t) else {
            return Vec::new();
        };
        let mut poly: Vec<V3> = tri.v.to_vec();
        for (plane, keep_beyond) in [(cam.near, true), (cam.far, false)] {
            let dist = |p: V3| {
                if keep_beyond {
                    cam.depth(p) - plane
                } else {
                    plane - cam.depth(p)
                }
            };
            let mut out = Vec::new();
            for i in 0..poly.len() {
                let (a, b) = (poly[(i + poly.len() - 1) % poly.len()], poly[i]);
                let (da, db) = (dist(a), dist(b));
                if (da >= 0.0) != (db >= 0.0) {
                    let s = da / (da - db);
                    out.push([0, 1, 2].map(|k| a[k] + (b[k] - a[k]) * s));
                }
                if db >= 0.0 {
                    out.push(b);
                }
            }
            poly = out;
        }
        poly.iter().filter_map(|&p| cam.project(p, w, h)).collect()
    }

    /// Casts the ray through screen point `(x, y)` of a `w × h` image.
    pub fn cast(&self, x: f64, y: f64, w: usize, h: usize) -> Option<Hit> {
        let dir = self.camera.ray(x, y, w, h);
        let mut best: Option<(f64, i32)> = None;
        if !self.bvh.nodes.is_empty() {
            let inv = dir.map(|c| 1.0 / c);
            let mut stack = vec![0u32];
            while let Some(n) = stack.pop() {
                let node = self.bvh.nodes[n as usize];
                let limit = best.map_or(self.camera.far, |(d, _)| d);
                // Box test against the ray parameter, which is the eye depth.
                if !node.bounds.hit(self.camera.eye, inv, limit) {
                    continue;
                }
                if node.count == 0 {
                    stack.push(node.first);
                    stack.push(node.first + 1);
                } else {
                    for &i in
                        &self.bvh.order[node.first as usize..(node.first + node.count) as usize]
                    {
                        if let Some(d) = self.hit_triangle_on(i as usize, dir, w, h) {
                            if best.is_none_or(|(bd, bid)| self.nearer(d, i as i32, bd, bid, w, h))
                            {
                                best = Some((d, i as i32));
                            }
                        }
                    }
                }
            }
        }
        let mut consider = |depth: f64, id: i32| {
            if best.is_none_or(|(d, _)| depth < d) {
                best = Some((depth, id));
            }
        };
        let base = self.triangles.len() as i32;
        for (k, s) in self.spheres.iter().enumerate() {
            if let Some(d) = hit_sphere(self.camera.eye, dir, s) {
                if d >= self.camera.near && d <= self.camera.far {
                    consider(d, base + k as i32);
                }
            }
        }
        let base = base + self.spheres.len() as i32;
        for (k, p) in self.planes.iter().enumerate() {
            if let Some(d) = hit_plane(self.camera.eye, dir, p) {
                if d >= self.camera.near && d <= self.camera.far {
                    consider(d, base + k as i32);
                }
            }
        }
        let (depth, id) = best?;
        let point = add(self.camera.eye, scale(dir, depth));
        let (color, normal) = self.surface(id, point);
        Some(Hit {
            id,
            depth,
            color: self.shade(color, normal),
        })
    }

    /// Base colour and unit geometric normal of object `id` at `point`.
    fn surface(&self, id: i32, point: V3) -> ([f64; 3], V3) {
        let nt = self.triangles.len() as i32;
        let ns = self.spheres.len() as i32;
        if id < nt {
            let t = &self.triangles[id as usize];
            let m = cross(sub(t.v[1], t.v[0]), sub(t.v[2], t.v[0]));
            let n = normalize(m).unwrap_or([0.0; 3]);
            let color = match self.vertex_colors.get(id as usize) {
                Some(c) => {
                    // Barycentric coordinates from the sub-triangles' areas along the normal.
                    let area = dot(m, m);
                    let b = [1, 2, 0].map(|k| {
                        let (a, b) = (t.v[k], t.v[(k + 1) % 3]);
                        dot(cross(sub(a, point), sub(b, point)), m) / area
                    });
                    [0, 1, 2].map(|ch| (0..3).map(|k| b[k] * c[k][ch]).sum())
                }
                None => t.color,
            };
            (color, n)
        } else if id < nt + ns {
            let s = &self.spheres[(id - nt) as usize];
            (s.color, normalize(sub(point, s.centre)).unwrap_or([0.0; 3]))
        } else {
            let p = &self.planes[(id - nt - ns) as usize];
            (p.color, p.normal)
        }
    }

    /// Renders every pixel centre of a `w × h` image.
    pub fn render(&self, w: usize, h: usize) -> Image {
        let mut img = Image {
            width: w,
            height: h,
            ids: vec![-1; w * h],
            depth: vec![f32::INFINITY; w * h],
            color: vec![[0; 3]; w * h],
        };
        for r in 0..h {
            for c in 0..w {
                if let Some(hit) = self.cast(c as f64 + 0.5, r as f64 + 0.5, w, h) {
                    let i = r * w + c;
                    img.ids[i] = hit.id;
                    img.depth[i] = hit.depth as f32;
                    img.color[i] = hit.color;
                }
            }
        }
        img
    }
}

/// Nearest ray parameter where `eye + t·dir` meets the sphere from outside (front surface), if
/// any; from inside, the far surface.
pub fn hit_sphere(eye: V3, dir: V3, s: &Sphere) -> Option<f64> {
    let oc = sub(eye, s.centre);
    let a = dot(dir, dir);
    let b = dot(oc, dir);
    let c = dot(oc, oc) - s.radius * s.radius;
    let disc = b * b - a * c;
    if disc < 0.0 {
        return None;
    }
    let root = disc.sqrt();
    let t0 = (-b - root) / a;
    let t1 = (-b + root) / a;
    if t0 > 0.0 {
        Some(t0)
    } else if t1 > 0.0 {
        Some(t1)
    } else {
        None
    }
}

/// Ray parameter where `eye + t·dir` meets the front of a one-sided plane.
pub fn hit_plane(eye: V3, dir: V3, p: &Plane) -> Option<f64> {
    let denom = dot(p.normal, dir);
    if denom >= 0.0 {
        return None;
    }
    let t = (p.d - dot(p.normal, eye)) / denom;
    (t > 0.0).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera::new([0.0, 0.0, 5.0], [0.0; 3], [0.0, 1.0, 0.0], 60.0, 0.1, 100.0).unwrap()
    }
    fn light() -> Light {
        Light {
            direction: [0.0, 0.0, 1.0],
            ambient: 0.2,
            diffuse: 0.8,
        }
    }

    #[test]
    fn ray_sphere_and_plane() {
        let s = Sphere {
            centre: [0.0; 3],
            radius: 1.0,
            color: [255.0; 3],
        };
        assert_eq!(hit_sphere([0.0, 0.0, 5.0], [0.0, 0.0, -1.0], &s), Some(4.0));
        assert_eq!(hit_sphere([0.0, 0.0, 5.0], [0.0, 1.0, 0.0], &s), None);
        assert_eq!(hit_sphere([0.0; 3], [0.0, 0.0, -1.0], &s), Some(1.0));
        let p = Plane {
            normal: [0.0, 1.0, 0.0],
            d: -1.0,
            color: [0.0; 3],
        };
        assert_eq!(hit_plane([0.0, 1.0, 0.0], [0.0, -1.0, 0.0], &p), Some(2.0));
        assert_eq!(hit_plane([0.0, 1.0, 0.0], [0.0, 1.0, 0.0], &p), None);
    }

    #[test]
    fn bvh_matches_brute_force() {
        // A deterministic soup of triangles.
        let mut tris = Vec::new();
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 33) as f64 / (1u64 << 31) as f64) * 2.0 - 1.0
        };
        for _ in 0..300 {
            let c = [rnd() * 2.0, rnd() * 2.0, rnd() * 2.0];
            tris.push(Triangle {
                v: [
                    c,
                    add(c, [rnd() * 0.5, rnd() * 0.5, rnd() * 0.5]),
                    add(c, [rnd() * 0.5, rnd() * 0.5, rnd() * 0.5]),
                ],
                color: [100.0; 3],
            });
        }
        let scene = Scene::new(tris.clone(), light(), camera(), false);
        let (w, h) = (40, 30);
        let img = scene.render(w, h);
        let mut hits = 0;
        for r in 0..h {
            for c in 0..w {
                let dir = scene.camera.ray(c as f64 + 0.5, r as f64 + 0.5, w, h);
                let brute = (0..tris.len())
                    .filter_map(|i| scene.hit_triangle_on(i, dir, w, h).map(|d| (d, i as i32)))
                    .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                assert_eq!(img.ids[r * w + c], brute.map_or(-1, |b| b.1));
                hits += brute.is_some() as usize;
            }
        }
        assert!(hits > 100);
    }

    #[test]
    fn lambert_shading_and_culling() {
        let t = Triangle {
            v: [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]],
            color: [200.0, 100.0, 50.0],
        };
        let back = Triangle {
            v: [t.v[0], t.v[2], t.v[1]],
            ..t
        };
        let scene = Scene::new(vec![t], light(), camera(), true);
        let hit = scene.cast(20.5, 20.5, 40, 40).unwrap();
        assert_eq!(hit.color, [200, 100, 50]);
        assert!((hit.depth - 5.0).abs() < 1e-9);
        let culled = Scene::new(vec![back], light(), camera(), true);
        assert!(culled.cast(20.5, 20.5, 40, 40).is_none());
        let kept = Scene::new(vec![back], light(), camera(), false);
        assert_eq!(kept.cast(20.5, 20.5, 40, 40).unwrap().color, [40, 20, 10]); // ambient only
    }

    #[test]
    fn projection_inverts_the_ray() {
        let cam = Camera::new(
            [1.0, 2.0, 3.0],
            [0.0, 0.5, -1.0],
            [0.0, 1.0, 0.0],
            45.0,
            0.1,
            50.0,
        )
        .unwrap();
        let dir = cam.ray(13.25, 7.5, 64, 48);
        let p = add(cam.eye, scale(dir, 4.0));
        let s = cam.project(p, 64, 48).unwrap();
        assert!((s[0] - 13.25).abs() < 1e-9 && (s[1] - 7.5).abs() < 1e-9);
        assert!((cam.depth(p) - 4.0).abs() < 1e-9);
    }
}
