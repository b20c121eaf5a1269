//! Vertex normals for meshes whose file has none: each corner gets the mean of the normals of the
//! faces around its vertex that are within the angle threshold of its own face (3ds Max's and
//! Blender's "auto smooth"), or that share a smoothing group with it (3DS files), each weighted
//! by the face's angle at that vertex (Thürmer and Wüthrich 1998), so a fan of thin triangles
//! weighs no more than one wide one.

use glam::Vec3;

use super::ModelMesh;

/// Newell's normal of face `f` (unit, or zero for a degenerate face): robust for non-planar
/// polygons.
pub fn face_normal(mesh: &ModelMesh, f: usize) -> Vec3 {
    let range = mesh.face(f);
    let mut n = Vec3::ZERO;
    let corners = &mesh.corners[range];
    for (k, &a) in corners.iter().enumerate() {
        let p = mesh.positions[a as usize];
        let q = mesh.positions[corners[(k + 1) % corners.len()] as usize];
        n += Vec3::new((p.y - q.y) * (p.z + q.z), (p.z - q.z) * (p.x + q.x), (p.x - q.x) * (p.y + q.y));
    }
    n.normalize_or_zero()
}

/// The angle of face `f` at its corner `c` (index into `corners`), radians.
fn corner_angle(mesh: &ModelMesh, f: usize, c: usize) -> f32 {
    let range = mesh.face(f);
    let n = range.len();
    let k = c - range.start;
    let prev = mesh.corners[range.start + (k + n - 1) % n] as usize;
    let next = mesh.corners[range.start + (k + 1) % n] as usize;
    let p = mesh.positions[mesh.corners[c] as usize];
    let (a, b) = ((mesh.positions[prev] - p).normalize_or_zero(), (mesh.positions[next] - p).normalize_or_zero());
    a.dot(b).clamp(-1.0, 1.0).acos()
}

/// One unit normal per corner of `mesh` (zero where every face around it is degenerate).
pub fn corner_normals(mesh: &ModelMesh, smooth_angle_deg: f32) -> Vec<Vec3> {
    let faces = mesh.face_count();
    let face_normals: Vec<Vec3> = (0..faces).map(|f| face_normal(mesh, f)).collect();
    let mut face_of_corner = vec![0u32; mesh.corners.len()];
    for f in 0..faces {
        for c in mesh.face(f) {
            face_of_corner[c] = f as u32;
        }
    }
    // Corners around each vertex, as a compressed list (counting sort by vertex).
    let mut start = vec![0u32; mesh.positions.len() + 1];
    for &v in &mesh.corners {
        start[v as usize + 1] += 1;
    }
    for i in 0..mesh.positions.len() {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut around = vec![0u32; mesh.corners.len()];
    for (c, &v) in mesh.corners.iter().enumerate() {
        around[fill[v as usize] as usize] = c as u32;
        fill[v as usize] += 1;
    }
    let weights: Vec<f32> =
        (0..mesh.corners.len()).map(|c| corner_angle(mesh, face_of_corner[c] as usize, c)).collect();
    let cos_limit = smooth_angle_deg.to_radians().cos();
    let mut out = vec![Vec3::ZERO; mesh.corners.len()];
    for (c, &v) in mesh.corners.iter().enumerate() {
        let f = face_of_corner[c] as usize;
        let nf = face_normals[f];
        if nf == Vec3::ZERO {
            continue;
        }
        let mut sum = Vec3::ZERO;
        for &d in &around[start[v as usize] as usize..start[v as usize + 1] as usize] {
            let g = face_of_corner[d as usize] as usize;
            let ng = face_normals[g];
            let joins = match &mesh.smoothing_groups {
                Some(groups) => g == f || groups[f] & groups[g] != 0,
                None => nf.dot(ng) >= cos_limit - 1e-6,
            };
            if joins {
                sum += ng * weights[d as usize];
            }
        }
        out[c] = sum.try_normalize().unwrap_or(nf);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Affine3A;

    /// A regular n-gon prism's side faces (quads around the y axis).
    fn prism(n: usize) -> ModelMesh {
        let mut mesh = ModelMesh { model_from_mesh: Affine3A::IDENTITY, ..Default::default() };
        for k in 0..n {
            let a = 2.0 * std::f32::consts::PI * k as f32 / n as f32;
            mesh.positions.push(Vec3::new(a.sin(), 0.0, a.cos()));
            mesh.positions.push(Vec3::new(a.sin(), 1.0, a.cos()));
        }
        for k in 0..n {
            let (a, b) = (2 * k as u32, 2 * ((k + 1) % n) as u32);
            mesh.push_face(&[a, b, b + 1, a + 1], None);
        }
        mesh
    }

    #[test]
    fn smooth_prism_normals_point_radially_within_the_threshold() {
        // 12 sides: neighbouring faces differ by 30 degrees.
        let mesh = prism(12);
        let smooth = corner_normals(&mesh, 31.0);
        for (c, &v) in mesh.corners.iter().enumerate() {
            let p = mesh.positions[v as usize];
            let radial = Vec3::new(p.x, 0.0, p.z).normalize();
            let err = smooth[c].dot(radial);
            assert!(err > 0.9999, "corner {c}: {} vs {radial}", smooth[c]);
        }
        let flat = corner_normals(&mesh, 29.0);
        for f in 0..mesh.face_count() {
            for c in mesh.face(f) {
                assert!(flat[c].dot(face_normal(&mesh, f)) > 0.9999, "below the threshold faces stay flat");
            }
        }
    }

    #[test]
    fn smoothing_groups_decide_instead_of_the_angle() {
        let mut mesh = prism(4);
        mesh.smoothing_groups = Some(vec![1, 1, 2, 2]);
        let n = corner_normals(&mesh, 0.0);
        // Faces 0 and 1 share group 1: their shared vertex gets the mean of both.
        let f0 = face_normal(&mesh, 0);
        let f1 = face_normal(&mesh, 1);
        let shared = mesh.face(0).find(|&c| mesh.face(1).any(|d| mesh.corners[d] == mesh.corners[c])).unwrap();
        assert!(n[shared].dot((f0 + f1).normalize()) > 0.9999);
        // Faces 1 and 2 do not: their shared vertex keeps face 1's normal in face 1.
        let c12 = mesh.face(1).find(|&c| mesh.face(2).any(|d| mesh.corners[d] == mesh.corners[c])).unwrap();
        assert!(n[c12].dot(f1) > 0.9999);
    }
}
