//! Subdivision surfaces on the host: Catmull-Clark (Catmull and Clark 1978; any polygons, quads
//! after one level) and Loop (Loop 1987; triangles), to a chosen level, with sharp creases
//! (Hoppe et al. 1994's crease rules: a crease edge splits at its midpoint, a vertex on two
//! crease edges follows the cubic B-spline of the crease, a vertex on three or more stays put).
//! Mesh boundaries are creases. After the last level every vertex moves to its limit position
//! and smooth vertices get the exact limit normal from the tangent masks (Halstead, Kass and
//! DeRose 1993 for Catmull-Clark; Loop's for Loop); crease and boundary vertices get the mean
//! of the limit faces' normals on each side of their creases. Texture coordinates are
//! interpolated linearly inside each face (face-varying, not smoothed).

use std::collections::HashMap;
use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use super::ModelMesh;

/// Most faces a subdivided mesh may reach (each level multiplies them by 4).
pub const MAX_SUBDIVIDED_FACES: usize = 1 << 24;
/// Most levels of subdivision.
pub const MAX_LEVELS: u32 = 8;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scheme {
    CatmullClark,
    Loop,
}

/// The edges of a mesh: their ends, the faces on each side, and which are creases.
struct Edges {
    ids: HashMap<u64, u32>,
    ends: Vec<[u32; 2]>,
    faces: Vec<Vec<u32>>,
    sharp: Vec<bool>,
}

fn key(a: u32, b: u32) -> u64 {
    ((a.min(b) as u64) << 32) | a.max(b) as u64
}

impl Edges {
    fn new(mesh: &ModelMesh, creases: &std::collections::HashSet<u64>) -> Edges {
        let mut e = Edges { ids: HashMap::new(), ends: Vec::new(), faces: Vec::new(), sharp: Vec::new() };
        for f in 0..mesh.face_count() {
            let c = &mesh.corners[mesh.face(f)];
            for k in 0..c.len() {
                let (a, b) = (c[k], c[(k + 1) % c.len()]);
                let id = *e.ids.entry(key(a, b)).or_insert_with(|| {
                    e.ends.push([a, b]);
                    e.faces.push(Vec::new());
                    e.sharp.push(false);
                    (e.ends.len() - 1) as u32
                });
                e.faces[id as usize].push(f as u32);
            }
        }
        for (id, faces) in e.faces.iter().enumerate() {
            let [a, b] = e.ends[id];
            e.sharp[id] = faces.len() != 2 || creases.contains(&key(a, b));
        }
        e
    }

    fn id(&self, a: u32, b: u32) -> u32 {
        self.ids[&key(a, b)]
    }
}

/// The crease edges of `mesh`: those whose faces' normals differ by more than `angle_deg`.
pub fn crease_edges(mesh: &ModelMesh, angle_deg: f32) -> std::collections::HashSet<u64> {
    let normals: Vec<Vec3> = (0..mesh.face_count()).map(|f| super::normals::face_normal(mesh, f)).collect();
    let edges = Edges::new(mesh, &Default::default());
    let cos_limit = angle_deg.to_radians().cos();
    let mut out = std::collections::HashSet::new();
    for (id, faces) in edges.faces.iter().enumerate() {
        if faces.len() == 2 && normals[faces[0] as usize].dot(normals[faces[1] as usize]) < cos_limit {
            let [a, b] = edges.ends[id];
            out.insert(key(a, b));
        }
    }
    out
}

/// Per vertex: its incident edges.
fn vertex_edges(vertices: usize, edges: &Edges) -> Vec<Vec<u32>> {
    let mut out = vec![Vec::new(); vertices];
    for (id, [a, b]) in edges.ends.iter().enumerate() {
        out[*a as usize].push(id as u32);
        out[*b as usize].push(id as u32);
    }
    out
}

/// The new positions of the old vertices under the crease rules: `Some` for a crease or corner
/// vertex, `None` for a smooth one (the scheme's own rule).
fn crease_rule(v: usize, p: &[Vec3], edges: &Edges, incident: &[u32], weights: (f32, f32)) -> Option<Vec3> {
    let sharp: Vec<u32> = incident.iter().copied().filter(|&e| edges.sharp[e as usize]).collect();
    match sharp.len() {
        0 | 1 => None,
        2 => {
            let other = |e: u32| {
                let [a, b] = edges.ends[e as usize];
                p[if a as usize == v { b } else { a } as usize]
            };
            Some(weights.0 * p[v] + weights.1 * (other(sharp[0]) + other(sharp[1])))
        }
        _ => Some(p[v]),
    }
}

/// One level of Catmull-Clark; returns the new mesh (all quads) and its crease edges.
fn catmull_clark_level(
    mesh: &ModelMesh,
    creases: &std::collections::HashSet<u64>,
) -> (ModelMesh, std::collections::HashSet<u64>) {
    let p = &mesh.positions;
    let (nv, nf) = (p.len(), mesh.face_count());
    let edges = Edges::new(mesh, creases);
    let ne = edges.ends.len();
    let face_points: Vec<Vec3> = (0..nf)
        .map(|f| {
            let c = &mesh.corners[mesh.face(f)];
            c.iter().map(|&i| p[i as usize]).sum::<Vec3>() / c.len() as f32
        })
        .collect();
    let edge_points: Vec<Vec3> = (0..ne)
        .map(|e| {
            let [a, b] = edges.ends[e];
            let mid = 0.5 * (p[a as usize] + p[b as usize]);
            if edges.sharp[e] {
                mid
            } else {
                let f = &edges.faces[e];
                0.5 * mid + 0.25 * (face_points[f[0] as usize] + face_points[f[1] as usize])
            }
        })
        .collect();
    let incident = vertex_edges(nv, &edges);
    let mut vertex_faces: Vec<Vec<u32>> = vec![Vec::new(); nv];
    for f in 0..nf {
        for &c in &mesh.corners[mesh.face(f)] {
            vertex_faces[c as usize].push(f as u32);
        }
    }
    let vertex_points: Vec<Vec3> = (0..nv)
        .map(|v| {
            if let Some(q) = crease_rule(v, p, &edges, &incident[v], (0.75, 0.125)) {
                return q;
            }
            let n = incident[v].len() as f32;
            if incident[v].is_empty() || vertex_faces[v].is_empty() {
                return p[v];
            }
            let q =
                vertex_faces[v].iter().map(|&f| face_points[f as usize]).sum::<Vec3>() / vertex_faces[v].len() as f32;
            let r = incident[v]
                .iter()
                .map(|&e| {
                    let [a, b] = edges.ends[e as usize];
                    0.5 * (p[a as usize] + p[b as usize])
                })
                .sum::<Vec3>()
                / n;
            (q + 2.0 * r + (n - 3.0) * p[v]) / n
        })
        .collect();

    let mut out = ModelMesh { name: mesh.name.clone(), model_from_mesh: mesh.model_from_mesh, ..Default::default() };
    out.positions = vertex_points;
    out.positions.extend(edge_points);
    out.positions.extend(face_points);
    let mut uvs = mesh.uvs.as_ref().map(|_| Vec::new());
    for f in 0..nf {
        let range = mesh.face(f);
        let c = &mesh.corners[range.clone()];
        let k = c.len();
        let fp = (nv + ne + f) as u32;
        let face_uv = mesh.uvs.as_ref().map(|uv| uv[range.clone()].iter().sum::<Vec2>() / k as f32);
        for i in 0..k {
            let (prev, cur, next) = (c[(i + k - 1) % k], c[i], c[(i + 1) % k]);
            let e_next = (nv as u32) + edges.id(cur, next);
            let e_prev = (nv as u32) + edges.id(prev, cur);
            out.push_face(&[cur, e_next, fp, e_prev], mesh.face_materials[f]);
            if let (Some(out_uv), Some(uv), Some(fuv)) = (&mut uvs, &mesh.uvs, face_uv) {
                let u = &uv[range.clone()];
                let (up, uc, un) = (u[(i + k - 1) % k], u[i], u[(i + 1) % k]);
                out_uv.extend([uc, 0.5 * (uc + un), fuv, 0.5 * (up + uc)]);
            }
        }
    }
    out.uvs = uvs;
    (out, split_sharp_edges(&edges, nv))
}

/// The two halves of each sharp interior edge after a step that put edge e's new vertex at
/// nv + e: creases stay creases on the next level.
fn split_sharp_edges(edges: &Edges, nv: usize) -> std::collections::HashSet<u64> {
    let mut sharp = std::collections::HashSet::new();
    for (e, [a, b]) in edges.ends.iter().enumerate() {
        if edges.sharp[e] && edges.faces[e].len() == 2 {
            let m = (nv + e) as u32;
            sharp.insert(key(*a, m));
            sharp.insert(key(m, *b));
        }
    }
    sharp
}

/// Loop's vertex weight beta for valence n.
fn loop_beta(n: f32) -> f32 {
    let c = 0.375 + 0.25 * (2.0 * PI / n).cos();
    (0.625 - c * c) / n
}

/// One level of Loop subdivision of a triangle mesh.
fn loop_level(
    mesh: &ModelMesh,
    creases: &std::collections::HashSet<u64>,
) -> (ModelMesh, std::collections::HashSet<u64>) {
    let p = &mesh.positions;
    let (nv, nf) = (p.len(), mesh.face_count());
    let edges = Edges::new(mesh, creases);
    let ne = edges.ends.len();
    let opposite = |f: u32, a: u32, b: u32| -> Vec3 {
        let c = &mesh.corners[mesh.face(f as usize)];
        p[*c.iter().find(|&&x| x != a && x != b).expect("a triangle has a third vertex") as usize]
    };
    let edge_points: Vec<Vec3> = (0..ne)
        .map(|e| {
            let [a, b] = edges.ends[e];
            let (pa, pb) = (p[a as usize], p[b as usize]);
            if edges.sharp[e] {
                0.5 * (pa + pb)
            } else {
                let f = &edges.faces[e];
                0.375 * (pa + pb) + 0.125 * (opposite(f[0], a, b) + opposite(f[1], a, b))
            }
        })
        .collect();
    let incident = vertex_edges(nv, &edges);
    let vertex_points: Vec<Vec3> = (0..nv)
        .map(|v| {
            if let Some(q) = crease_rule(v, p, &edges, &incident[v], (0.75, 0.125)) {
                return q;
            }
            if incident[v].is_empty() {
                return p[v];
            }
            let n = incident[v].len() as f32;
            let beta = loop_beta(n);
            let ring: Vec3 = incident[v]
                .iter()
                .map(|&e| {
                    let [a, b] = edges.ends[e as usize];
                    p[if a as usize == v { b } else { a } as usize]
                })
                .sum();
            (1.0 - n * beta) * p[v] + beta * ring
        })
        .collect();
    let mut out = ModelMesh { name: mesh.name.clone(), model_from_mesh: mesh.model_from_mesh, ..Default::default() };
    out.positions = vertex_points;
    out.positions.extend(edge_points);
    let mut uvs = mesh.uvs.as_ref().map(|_| Vec::new());
    for f in 0..nf {
        let range = mesh.face(f);
        let [a, b, c] = [mesh.corners[range.start], mesh.corners[range.start + 1], mesh.corners[range.start + 2]];
        let e = |x: u32, y: u32| nv as u32 + edges.id(x, y);
        let (ab, bc, ca) = (e(a, b), e(b, c), e(c, a));
        let material = mesh.face_materials[f];
        for t in [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]] {
            out.push_face(&t, material);
        }
        if let (Some(out_uv), Some(uv)) = (&mut uvs, &mesh.uvs) {
            let [ua, ub, uc] = [uv[range.start], uv[range.start + 1], uv[range.start + 2]];
            let (uab, ubc, uca) = (0.5 * (ua + ub), 0.5 * (ub + uc), 0.5 * (uc + ua));
            out_uv.extend([ua, uab, uca, ub, ubc, uab, uc, uca, ubc, uab, ubc, uca]);
        }
    }
    out.uvs = uvs;
    (out, split_sharp_edges(&edges, nv))
}

/// Why a mesh cannot be subdivided.
#[derive(Debug, Clone, PartialEq)]
pub enum SubdivideError {
    /// Loop subdivision met a face that is not a triangle.
    NotTriangles { face: usize, corners: usize },
    /// The result would pass `MAX_SUBDIVIDED_FACES`.
    TooManyFaces { faces: usize },
}

impl std::fmt::Display for SubdivideError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SubdivideError::NotTriangles { face, corners } => write!(
                f,
                "Loop subdivision needs triangles, but face {face} has {corners} corners; use `subdivision = \"catmull-clark\"`"
            ),
            SubdivideError::TooManyFaces { faces } => write!(
                f,
                "subdividing would make {faces} faces, more than {MAX_SUBDIVIDED_FACES}; lower `levels`"
            ),
        }
    }
}

/// `mesh` subdivided `levels` times by `scheme`, its edges sharper than `crease_angle_deg`
/// (when given) kept as creases, moved to the limit surface, with per-corner limit normals.
/// File normals are dropped (they belong to the control mesh).
pub fn subdivide(
    mesh: &ModelMesh,
    scheme: Scheme,
    levels: u32,
    crease_angle_deg: Option<f32>,
) -> Result<ModelMesh, SubdivideError> {
    if scheme == Scheme::Loop {
        if let Some(f) = (0..mesh.face_count()).find(|&f| mesh.face(f).len() != 3) {
            return Err(SubdivideError::NotTriangles { face: f, corners: mesh.face(f).len() });
        }
    }
    let mut faces = match scheme {
        Scheme::CatmullClark => mesh.corners.len(),
        Scheme::Loop => mesh.face_count() * 4,
    };
    for _ in 1..levels {
        faces = faces.saturating_mul(4);
    }
    if levels > 0 && faces > MAX_SUBDIVIDED_FACES {
        return Err(SubdivideError::TooManyFaces { faces });
    }
    let mut creases = crease_angle_deg.map(|a| crease_edges(mesh, a)).unwrap_or_default();
    let mut current = mesh.clone();
    current.normals = None;
    for _ in 0..levels {
        let (next, sharp) = match scheme {
            Scheme::CatmullClark => catmull_clark_level(&current, &creases),
            Scheme::Loop => loop_level(&current, &creases),
        };
        current = next;
        creases = sharp;
    }
    limit(&mut current, scheme, &creases);
    Ok(current)
}

/// Moves every vertex to its limit position and sets per-corner limit normals.
fn limit(mesh: &mut ModelMesh, scheme: Scheme, creases: &std::collections::HashSet<u64>) {
    let edges = Edges::new(mesh, creases);
    let nv = mesh.positions.len();
    let incident = vertex_edges(nv, &edges);
    // Corners around each vertex: (face, position of the vertex in the face).
    let mut around: Vec<Vec<(u32, u32)>> = vec![Vec::new(); nv];
    for f in 0..mesh.face_count() {
        let r = mesh.face(f);
        for (k, &v) in mesh.corners[r].iter().enumerate() {
            around[v as usize].push((f as u32, k as u32));
        }
    }
    let corner = |f: u32, k: i64| -> u32 {
        let r = mesh.face(f as usize);
        let n = r.len() as i64;
        mesh.corners[r.start + k.rem_euclid(n) as usize]
    };
    let p = mesh.positions.clone();
    let mut limit_positions = p.clone();
    let mut smooth_normal = vec![None; nv];
    for v in 0..nv {
        let ring_edges = &incident[v];
        let other = |e: u32| {
            let [a, b] = edges.ends[e as usize];
            if a as usize == v {
                b
            } else {
                a
            }
        };
        // Crease and corner vertices: the B-spline limit of their crease, or fixed.
        let sharp: Vec<u32> = ring_edges.iter().copied().filter(|&e| edges.sharp[e as usize]).collect();
        if sharp.len() >= 2 {
            limit_positions[v] = if sharp.len() == 2 {
                (p[other(sharp[0]) as usize] + 4.0 * p[v] + p[other(sharp[1]) as usize]) / 6.0
            } else {
                p[v]
            };
            continue;
        }
        // Order the faces around the vertex: the face after face j has prev = face j's next.
        let faces = &around[v];
        let n = faces.len();
        if n < 3 || ring_edges.len() != n {
            continue;
        }
        let mut order = vec![faces[0]];
        while order.len() < n {
            let (f, k) = *order.last().expect("starts with one face");
            let next = corner(f, k as i64 + 1);
            match faces.iter().find(|&&(g, j)| corner(g, j as i64 - 1) == next) {
                Some(&found) if found != order[0] => order.push(found),
                _ => break,
            }
        }
        if order.len() != n {
            continue;
        }
        let nf = n as f32;
        let (mut t1, mut t2) = (Vec3::ZERO, Vec3::ZERO);
        match scheme {
            Scheme::CatmullClark => {
                if order.iter().any(|&(f, _)| mesh.face(f as usize).len() != 4) {
                    continue;
                }
                // e_j: the edge neighbour before face j; f_j: face j's diagonal corner.
                let e: Vec<Vec3> = order.iter().map(|&(f, k)| p[corner(f, k as i64 - 1) as usize]).collect();
                let d: Vec<Vec3> = order.iter().map(|&(f, k)| p[corner(f, k as i64 + 2) as usize]).collect();
                let sum_e: Vec3 = e.iter().sum();
                let sum_d: Vec3 = d.iter().sum();
                limit_positions[v] = (nf * nf * p[v] + 4.0 * sum_e + sum_d) / (nf * (nf + 5.0));
                let a = 1.0 + (2.0 * PI / nf).cos() + (PI / nf).cos() * (2.0 * (9.0 + (2.0 * PI / nf).cos())).sqrt();
                for j in 0..n {
                    let (t0, t1a) = (2.0 * PI * j as f32 / nf, 2.0 * PI * (j + 1) as f32 / nf);
                    t1 += a * t0.cos() * e[j] + (t0.cos() + t1a.cos()) * d[j];
                    t2 += a * t0.sin() * e[j] + (t0.sin() + t1a.sin()) * d[j];
                }
            }
            Scheme::Loop => {
                let q: Vec<Vec3> = order.iter().map(|&(f, k)| p[corner(f, k as i64 - 1) as usize]).collect();
                let beta = loop_beta(nf);
                let chi = 1.0 / (3.0 / (8.0 * beta) + nf);
                limit_positions[v] = (1.0 - nf * chi) * p[v] + chi * q.iter().sum::<Vec3>();
                for (j, qj) in q.iter().enumerate() {
                    let t = 2.0 * PI * j as f32 / nf;
                    t1 += t.cos() * *qj;
                    t2 += t.sin() * *qj;
                }
            }
        }
        smooth_normal[v] = t1.cross(t2).try_normalize();
    }
    mesh.positions = limit_positions;
    // Normals: the limit faces' mean on each side of a crease, the exact limit normal at smooth
    // vertices (turned to the faces' side: the ring's direction decides the cross product's).
    let crease_mesh_normals = corner_normals_by_creases(mesh, &edges);
    let mut normals = crease_mesh_normals;
    for (c, &v) in mesh.corners.iter().enumerate() {
        if let Some(n) = smooth_normal[v as usize] {
            normals[c] = if n.dot(normals[c]) < 0.0 { -n } else { n };
        }
    }
    mesh.normals = Some(normals);
}

/// Per-corner normals: the angle-weighted mean of the normals of the faces reachable around the
/// vertex without crossing a crease edge.
fn corner_normals_by_creases(mesh: &ModelMesh, edges: &Edges) -> Vec<Vec3> {
    let face_normals: Vec<Vec3> = (0..mesh.face_count()).map(|f| super::normals::face_normal(mesh, f)).collect();
    // Union the faces around each vertex across smooth edges: label corners by a union-find.
    let mut parent: Vec<u32> = (0..mesh.corners.len() as u32).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            parent[x as usize] = parent[parent[x as usize] as usize];
            x = parent[x as usize];
        }
        x
    }
    for (e, faces) in edges.faces.iter().enumerate() {
        if edges.sharp[e] {
            continue;
        }
        let [a, b] = edges.ends[e];
        for v in [a, b] {
            let cs: Vec<u32> = faces
                .iter()
                .filter_map(|&f| mesh.face(f as usize).find(|&c| mesh.corners[c] == v).map(|c| c as u32))
                .collect();
            for w in cs.windows(2) {
                let (x, y) = (find(&mut parent, w[0]), find(&mut parent, w[1]));
                parent[x as usize] = y;
            }
        }
    }
    let mut face_of_corner = vec![0usize; mesh.corners.len()];
    for f in 0..mesh.face_count() {
        for c in mesh.face(f) {
            face_of_corner[c] = f;
        }
    }
    let mut sums: HashMap<u32, Vec3> = HashMap::new();
    for c in 0..mesh.corners.len() {
        let root = find(&mut parent, c as u32);
        *sums.entry(root).or_default() += face_normals[face_of_corner[c]];
    }
    (0..mesh.corners.len())
        .map(|c| {
            let root = find(&mut parent, c as u32);
            sums[&root].try_normalize().unwrap_or(face_normals[face_of_corner[c]])
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Affine3A;

    fn cube() -> ModelMesh {
        let mut m = ModelMesh { model_from_mesh: Affine3A::IDENTITY, ..Default::default() };
        for i in 0..8 {
            m.positions.push(Vec3::new(
                (i & 1) as f32 * 2.0 - 1.0,
                ((i >> 1) & 1) as f32 * 2.0 - 1.0,
                ((i >> 2) & 1) as f32 * 2.0 - 1.0,
            ));
        }
        for f in [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]] {
            m.push_face(&f, None);
        }
        m
    }

    fn octahedron() -> ModelMesh {
        let mut m = ModelMesh { model_from_mesh: Affine3A::IDENTITY, ..Default::default() };
        m.positions = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        for f in [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]] {
            m.push_face(&f, None);
        }
        m
    }

    /// Every limit normal is within `degrees` of the normal of the faces around its vertex, and
    /// points outward (the meshes are convex around the origin).
    fn check(mesh: &ModelMesh, degrees: f32) {
        let normals = mesh.normals.as_ref().unwrap();
        for f in 0..mesh.face_count() {
            let fnorm = super::super::normals::face_normal(mesh, f);
            for c in mesh.face(f) {
                let p = mesh.positions[mesh.corners[c] as usize];
                assert!(normals[c].dot(p) > 0.0, "outward at {p}");
                assert!(normals[c].dot(fnorm) > degrees.to_radians().cos(), "{} vs face {fnorm}", normals[c]);
            }
        }
    }

    #[test]
    fn catmull_clark_cube_converges_to_a_smooth_closed_surface() {
        let m = subdivide(&cube(), Scheme::CatmullClark, 3, None).unwrap();
        assert_eq!(m.face_count(), 6 * 4usize.pow(3));
        check(&m, 12.0);
        // Symmetric: the limit surface of the cube passes the face centres at the same distance.
        let r: Vec<f32> = [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X]
            .iter()
            .map(|d| m.positions.iter().map(|p| p.dot(*d)).fold(f32::MIN, f32::max))
            .collect();
        assert!(r.iter().all(|x| (x - r[0]).abs() < 1e-5), "{r:?}");
    }

    #[test]
    fn loop_octahedron_is_smooth_and_crease_angle_keeps_a_cube_sharp() {
        let m = subdivide(&octahedron(), Scheme::Loop, 3, None).unwrap();
        assert_eq!(m.face_count(), 8 * 64);
        check(&m, 12.0);
        // With every cube edge a crease, Catmull-Clark keeps the cube's faces flat.
        let sharp = subdivide(&cube(), Scheme::CatmullClark, 2, Some(45.0)).unwrap();
        for p in &sharp.positions {
            assert!((p.abs().max_element() - 1.0).abs() < 1e-5, "{p} left the cube's faces");
        }
    }

    #[test]
    fn loop_refuses_quads_and_levels_are_bounded() {
        assert!(matches!(subdivide(&cube(), Scheme::Loop, 1, None), Err(SubdivideError::NotTriangles { .. })));
        assert!(matches!(subdivide(&cube(), Scheme::CatmullClark, 12, None), Err(SubdivideError::TooManyFaces { .. })));
    }

    #[test]
    fn limit_normal_of_a_regular_vertex_matches_the_surface() {
        // A flat grid stays flat: limit normals are the plane's.
        let mut m = ModelMesh { model_from_mesh: Affine3A::IDENTITY, ..Default::default() };
        for j in 0..5 {
            for i in 0..5 {
                m.positions.push(Vec3::new(i as f32, j as f32, 0.0));
            }
        }
        for j in 0..4u32 {
            for i in 0..4u32 {
                let a = j * 5 + i;
                m.push_face(&[a, a + 1, a + 6, a + 5], None);
            }
        }
        let s = subdivide(&m, Scheme::CatmullClark, 2, None).unwrap();
        for n in s.normals.unwrap() {
            assert!(n.abs_diff_eq(Vec3::Z, 1e-5), "{n}");
        }
    }
}
