use rapier3d::math::{Pose, Rotation, Vector};

/// A solid the renderer can draw, in world coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// Capped cylinder between two points.
    Cylinder { a: Vector, b: Vector, radius: f32 },
    /// Cylinder with hemispherical ends between two points.
    Capsule { a: Vector, b: Vector, radius: f32 },
    /// Box with a centre, orientation and half extents.
    Cuboid {
        center: Vector,
        rotation: Rotation,
        half: Vector,
    },
}

impl Shape {
    /// The same shape moved by `pose` (shapes are described in their body's frame).
    pub fn transformed(&self, pose: &Pose) -> Shape {
        match *self {
            Shape::Cylinder { a, b, radius } => Shape::Cylinder {
                a: pose * a,
                b: pose * b,
                radius,
            },
            Shape::Capsule { a, b, radius } => Shape::Capsule {
                a: pose * a,
                b: pose * b,
                radius,
            },
            Shape::Cuboid {
                center,
                rotation,
                half,
            } => Shape::Cuboid {
                center: pose * center,
                rotation: pose.rotation * rotation,
                half,
            },
        }
    }

    /// Centre and radius of a sphere enclosing the shape (for screen-space culling).
    fn bounding_sphere(&self) -> (Vector, f32) {
        match *self {
            Shape::Cylinder { a, b, radius } => ((a + b) * 0.5, (b - a).length() * 0.5 + radius),
            Shape::Capsule { a, b, radius } => ((a + b) * 0.5, (b - a).length() * 0.5 + radius),
            Shape::Cuboid { center, half, .. } => (center, half.length()),
        }
    }

    /// Nearest hit of the ray `ro + t·rd` (rd unit) with t > 0: (t, unit normal).
    fn intersect(&self, ro: Vector, rd: Vector) -> Option<(f32, Vector)> {
        match *self {
            Shape::Cylinder { a, b, radius } => cylinder(ro, rd, a, b, radius),
            Shape::Capsule { a, b, radius } => capsule(ro, rd, a, b, radius),
            Shape::Cuboid {
                center,
                rotation,
                half,
            } => cuboid(ro, rd, center, rotation, half),
        }
    }
}

/// A shape with its colour (linear RGB in [0, 1]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Primitive {
    pub shape: Shape,
    pub color: [f32; 3],
}

/// Fixed perspective camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    pub eye: Vector,
    pub target: Vector,
    /// Vertical field of view, radians.
    pub fov_y: f32,
}

/// The table top: a dark rectangle at z = 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Table {
    pub x: [f32; 2],
    pub y: [f32; 2],
    pub color: [f32; 3],
}

/// Samples per pixel along each axis: 2×2 supersampling smooths edges like the original's
/// downscaled frames.
const SUPERSAMPLE: usize = 2;

/// Pure-Rust ray caster for the scene's few analytic solids.
///
/// Each primitive is only tested against the pixels inside its projected bounding box, so a
/// frame costs about the area the solids cover. Only IEEE-exact operations (+, −, ×, ÷, √) run
/// per pixel, which makes frames bit-identical natively and in wasm.
#[derive(Debug, Clone)]
pub struct Renderer {
    size: usize,
    camera: Camera,
    right: Vector,
    up: Vector,
    forward: Vector,
    focal: f32,
    table: Table,
    rays: Vec<Vector>,
    depth: Vec<f32>,
    normal: Vec<Vector>,
    color: Vec<[f32; 3]>,
}

/// Light direction (towards the light), ambient and diffuse weights.
const LIGHT: [f32; 3] = [-0.35, -0.55, 0.76];
const AMBIENT: f32 = 0.38;
const DIFFUSE: f32 = 0.62;

impl Renderer {
    /// A renderer producing `size × size` frames.
    pub fn new(size: u32, camera: Camera, table: Table) -> Renderer {
        let n = size as usize * SUPERSAMPLE;
        let forward = (camera.target - camera.eye).normalize();
        let right = forward.cross(Vector::Z).normalize();
        let up = right.cross(forward);
        let focal = n as f32 * 0.5 / libm::tanf(camera.fov_y * 0.5);
        let mut rays = Vec::with_capacity(n * n);
        for py in 0..n {
            for px in 0..n {
                let x = px as f32 + 0.5 - n as f32 * 0.5;
                let y = n as f32 * 0.5 - (py as f32 + 0.5);
                rays.push((forward * focal + right * x + up * y).normalize());
            }
        }
        Renderer {
            size: size as usize,
            camera,
            right,
            up,
            forward,
            focal,
            table,
            rays,
            depth: vec![0.0; n * n],
            normal: vec![Vector::ZERO; n * n],
            color: vec![[0.0; 3]; n * n],
        }
    }

    /// Frame size in pixels.
    pub fn size(&self) -> u32 {
        self.size as u32
    }

    /// Draw `primitives` over the table into `out` (`size² × 3` RGB bytes).
    pub fn render(&mut self, primitives: &[Primitive], out: &mut [u8]) {
        let n = self.size * SUPERSAMPLE;
        let eye = self.camera.eye;
        let t = self.table;
        for i in 0..n * n {
            let rd = self.rays[i];
            self.depth[i] = f32::INFINITY;
            if rd.z < 0.0 {
                let d = -eye.z / rd.z;
                let (x, y) = (eye.x + rd.x * d, eye.y + rd.y * d);
                if x >= t.x[0] && x <= t.x[1] && y >= t.y[0] && y <= t.y[1] {
                    self.depth[i] = d;
                    self.normal[i] = Vector::Z;
                    self.color[i] = t.color;
                }
            }
        }
        for p in primitives {
            let Some([x0, y0, x1, y1]) = self.screen_bounds(&p.shape) else {
                continue;
            };
            for py in y0..y1 {
                for px in x0..x1 {
                    let i = py * n + px;
                    if let Some((d, nrm)) = p.shape.intersect(eye, self.rays[i]) {
                        if d < self.depth[i] {
                            self.depth[i] = d;
                            self.normal[i] = nrm;
                            self.color[i] = p.color;
                        }
                    }
                }
            }
        }
        self.resolve(out);
    }

    /// Shade the samples and average each pixel's 2×2 block.
    fn resolve(&self, out: &mut [u8]) {
        let n = self.size * SUPERSAMPLE;
        let light = Vector::from(LIGHT).normalize();
        let weight = 1.0 / (SUPERSAMPLE * SUPERSAMPLE) as f32;
        for y in 0..self.size {
            for x in 0..self.size {
                let mut acc = [0.0f32; 3];
                for sy in 0..SUPERSAMPLE {
                    for sx in 0..SUPERSAMPLE {
                        let i = (y * SUPERSAMPLE + sy) * n + x * SUPERSAMPLE + sx;
                        if self.depth[i] == f32::INFINITY {
                            continue;
                        }
                        let lambert = self.normal[i].dot(light).max(0.0);
                        let shade = AMBIENT + DIFFUSE * lambert;
                        for (a, c) in acc.iter_mut().zip(self.color[i]) {
                            *a += c * shade;
                        }
                    }
                }
                let o = (y * self.size + x) * 3;
                for c in 0..3 {
                    out[o + c] = ((acc[c] * weight).clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
                }
            }
        }
    }

    /// Pixel rectangle `[x0, y0, x1, y1)` that may contain the shape, or None when off screen.
    fn screen_bounds(&self, shape: &Shape) -> Option<[usize; 4]> {
        let n = (self.size * SUPERSAMPLE) as f32;
        let (c, r) = shape.bounding_sphere();
        let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
        for k in 0..8 {
            let corner = c + Vector::new(
                if k & 1 == 0 { -r } else { r },
                if k & 2 == 0 { -r } else { r },
                if k & 4 == 0 { -r } else { r },
            );
            let v = corner - self.camera.eye;
            let z = v.dot(self.forward);
            if z < 1e-3 {
                return Some([0, 0, n as usize, n as usize]);
            }
            let x = v.dot(self.right) / z * self.focal + n * 0.5;
            let y = n * 0.5 - v.dot(self.up) / z * self.focal;
            lo = [lo[0].min(x), lo[1].min(y)];
            hi = [hi[0].max(x), hi[1].max(y)];
        }
        if hi[0] < 0.0 || hi[1] < 0.0 || lo[0] >= n || lo[1] >= n {
            return None;
        }
        let clamp = |v: f32| v.clamp(0.0, n) as usize;
        Some([
            clamp(lo[0]),
            clamp(lo[1]),
            clamp(hi[0] + 1.0),
            clamp(hi[1] + 1.0),
        ])
    }
}

/// The ray's quadratic against the infinite cylinder of radius `r` around the line a→b,
/// shared by the capsule and the capped cylinder (after Inigo Quilez's closed forms).
struct AxisQuadratic {
    ba: Vector,
    oa: Vector,
    baba: f32,
    bard: f32,
    baoa: f32,
    /// Quadratic coefficients `qa t² + 2 qb t + qc` and its discriminant `qb² − qa qc`.
    qa: f32,
    qb: f32,
    h: f32,
}

impl AxisQuadratic {
    fn new(ro: Vector, rd: Vector, a: Vector, b: Vector, r: f32) -> AxisQuadratic {
        let ba = b - a;
        let oa = ro - a;
        let baba = ba.dot(ba);
        let bard = ba.dot(rd);
        let baoa = ba.dot(oa);
        let qa = baba - bard * bard;
        let qb = baba * rd.dot(oa) - baoa * bard;
        let qc = baba * oa.dot(oa) - baoa * baoa - r * r * baba;
        AxisQuadratic {
            ba,
            oa,
            baba,
            bard,
            baoa,
            qa,
            qb,
            h: qb * qb - qa * qc,
        }
    }
}

/// Ray against a capsule.
fn capsule(ro: Vector, rd: Vector, a: Vector, b: Vector, r: f32) -> Option<(f32, Vector)> {
    let AxisQuadratic {
        ba,
        oa,
        baba,
        bard,
        baoa,
        qa,
        qb,
        h,
    } = AxisQuadratic::new(ro, rd, a, b, r);
    if h < 0.0 {
        return None;
    }
    let mut t = (-qb - h.sqrt()) / qa;
    let y = baoa + t * bard;
    if !(y > 0.0 && y < baba) {
        // Hemispherical caps.
        let oc = if y <= 0.0 { oa } else { ro - b };
        let b2 = rd.dot(oc);
        let h2 = b2 * b2 - (oc.dot(oc) - r * r);
        if h2 <= 0.0 {
            return None;
        }
        t = -b2 - h2.sqrt();
    }
    if t.is_nan() || t <= 0.0 {
        return None;
    }
    let p = ro + rd * t - a;
    let k = (p.dot(ba) / baba).clamp(0.0, 1.0);
    Some((t, (p - ba * k) / r))
}

/// Ray against a capped cylinder.
fn cylinder(ro: Vector, rd: Vector, a: Vector, b: Vector, r: f32) -> Option<(f32, Vector)> {
    let AxisQuadratic {
        ba,
        oa,
        baba,
        bard,
        baoa,
        qa,
        qb,
        h,
    } = AxisQuadratic::new(ro, rd, a, b, r);
    if h < 0.0 || qa <= 1e-12 {
        return None;
    }
    let h = h.sqrt();
    let t = (-qb - h) / qa;
    let y = baoa + t * bard;
    if y > 0.0 && y < baba {
        if t <= 0.0 {
            return None;
        }
        return Some((t, (oa + rd * t - ba * (y / baba)) / r));
    }
    let t = (if y < 0.0 { 0.0 } else { baba } - baoa) / bard;
    if t > 0.0 && (qb + qa * t).abs() < h {
        let sign = if y < 0.0 { -1.0 } else { 1.0 };
        return Some((t, ba * (sign / baba.sqrt())));
    }
    None
}

/// Ray against an oriented box (slab test in the box's frame).
fn cuboid(ro: Vector, rd: Vector, c: Vector, rot: Rotation, half: Vector) -> Option<(f32, Vector)> {
    let inv = rot.inverse();
    let o = inv * (ro - c);
    let d = inv * rd;
    let m = Vector::ONE / d;
    let n = m * o;
    let k = m.abs() * half;
    let t1 = -n - k;
    let t2 = -n + k;
    let tn = t1.x.max(t1.y).max(t1.z);
    let tf = t2.x.min(t2.y).min(t2.z);
    if tn > tf || tf < 0.0 || tn <= 0.0 {
        return None;
    }
    let local = if tn == t1.x {
        Vector::new(-d.x.signum(), 0.0, 0.0)
    } else if tn == t1.y {
        Vector::new(0.0, -d.y.signum(), 0.0)
    } else {
        Vector::new(0.0, 0.0, -d.z.signum())
    };
    Some((tn, rot * local))
}
