//! Bicubic Bezier patches (POV-Ray's `bicubic_patch`, the Utah teapot's patch set), tessellated
//! on the host into triangles with the patches' own normals.
//!
//! A patch of 4 x 4 control points P(i, j) is sampled on an n x n grid of (u, v). The chord of a
//! cubic Bezier curve over a parameter step h deviates from the curve by at most
//! h^2 / 8 max |C''| (the linear interpolation error), and |C''| <= 6 max |second difference of
//! the control points|, so a grid of n = ceil(sqrt(6 (Du + Dv) / (8 tol))) steps per side, with Du and Dv the
//! largest second differences along u and along v, stays within `tol` of the surface. All patches of one shape share the largest n, so
//! neighbours that share an edge share its samples and leave no cracks.
//!
//! `.bpt` files (Newell's teapot in the form the SIGGRAPH course notes spread): the patch count,
//! then per patch `3 3` (the degrees) and 16 lines of `x y z`, rows of constant v.

use std::path::Path;

use glam::{Affine3A, Vec3};

use super::{check_number, Model, ModelError, ModelMesh};

/// Most grid steps per patch side (a tolerance far below the patch's size asks for no more).
pub const MAX_PATCH_STEPS: u32 = 256;
/// Most patches in one file or shape.
pub const MAX_PATCHES: usize = 1 << 20;
/// Most grid cells (two triangles each) one tessellation makes: 2 M triangles, seconds of work.
/// Every patch gets the finest patch's steps (so neighbours meet without cracks), and one wild
/// control point would otherwise ask for 256 x 256 cells on every patch of the file.
pub const MAX_PATCH_CELLS: u64 = 1 << 20;

/// The point and the (unnormalised) normal of the patch at (u, v).
pub fn evaluate(p: &[Vec3; 16], u: f32, v: f32) -> (Vec3, Vec3) {
    let basis = |t: f32| {
        let s = 1.0 - t;
        [s * s * s, 3.0 * s * s * t, 3.0 * s * t * t, t * t * t]
    };
    let derivative = |t: f32| {
        let s = 1.0 - t;
        [-3.0 * s * s, 3.0 * s * s - 6.0 * s * t, 6.0 * s * t - 3.0 * t * t, 3.0 * t * t]
    };
    let (bu, bv, du, dv) = (basis(u), basis(v), derivative(u), derivative(v));
    let (mut x, mut dxu, mut dxv) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
    for j in 0..4 {
        for i in 0..4 {
            let c = p[4 * j + i];
            x += bu[i] * bv[j] * c;
            dxu += du[i] * bv[j] * c;
            dxv += bu[i] * dv[j] * c;
        }
    }
    (x, dxu.cross(dxv))
}

/// Grid steps per side that keep one patch within `tolerance` of its triangles.
pub fn steps_for(p: &[Vec3; 16], tolerance: f32) -> u32 {
    let (mut du, mut dv) = (0.0f32, 0.0f32);
    for j in 0..4 {
        for i in 0..2 {
            du = du.max((p[4 * j + i] - 2.0 * p[4 * j + i + 1] + p[4 * j + i + 2]).length());
            dv = dv.max((p[4 * i + j] - 2.0 * p[4 * (i + 1) + j] + p[4 * (i + 2) + j]).length());
        }
    }
    // Bilinear (and linear) interpolation over a cell of side h errs by at most
    // h^2 / 8 (max |S_uu| + max |S_vv|), with |S_uu| <= 6 du and |S_vv| <= 6 dv.
    let n = (6.0 * (du + dv) / (8.0 * tolerance)).sqrt().ceil();
    if n.is_finite() {
        (n as u32).clamp(1, MAX_PATCH_STEPS)
    } else {
        MAX_PATCH_STEPS
    }
}

/// The patches as one mesh of quads (each grid cell), with per-corner normals from the patches'
/// derivatives. Where a patch edge collapses to a point (the teapot's lid and bottom) the normal
/// there is the limit from inside the patch. An error says when the tolerance asks for more than
/// `MAX_PATCH_CELLS`.
pub fn tessellate(patches: &[[Vec3; 16]], tolerance: f32) -> Result<ModelMesh, String> {
    let n = patches.iter().map(|p| steps_for(p, tolerance)).max().unwrap_or(1);
    let cells = patches.len() as u64 * u64::from(n) * u64::from(n);
    if cells > MAX_PATCH_CELLS {
        return Err(format!(
            "{} patches of {n} x {n} cells each ({cells} cells) meet the flatness {}; the most is {MAX_PATCH_CELLS}: \
             raise `flatness`, or check the control points (one far from the others makes every patch fine)",
            patches.len(),
            crate::limits::fmt_f32(tolerance)
        ));
    }
    let mut mesh = ModelMesh { model_from_mesh: Affine3A::IDENTITY, ..Default::default() };
    let mut corner_normals = Vec::new();
    for p in patches {
        let base = mesh.positions.len() as u32;
        let mut grid_normals = Vec::with_capacity(((n + 1) * (n + 1)) as usize);
        for j in 0..=n {
            for i in 0..=n {
                let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
                let (x, mut normal) = evaluate(p, u, v);
                // A degenerate edge: step inside the patch until the normal is defined.
                let mut step = 1e-3;
                while normal.length_squared() < 1e-20 && step < 0.5 {
                    let (_, inner) = evaluate(p, (u - 0.5) * (1.0 - step) + 0.5, (v - 0.5) * (1.0 - step) + 0.5);
                    normal = inner;
                    step *= 4.0;
                }
                mesh.positions.push(x);
                grid_normals.push(normal.normalize_or_zero());
            }
        }
        for j in 0..n {
            for i in 0..n {
                let a = base + j * (n + 1) + i;
                let quad = [a, a + 1, a + n + 2, a + n + 1];
                mesh.push_face(&quad, None);
                corner_normals.extend(quad.iter().map(|&q| grid_normals[(q - base) as usize]));
            }
        }
    }
    mesh.normals = Some(corner_normals);
    Ok(mesh)
}

/// The model of a `.bpt` file's bytes.
pub fn parse_bpt(bytes: &[u8], path: &Path, tolerance: f32) -> Result<Model, ModelError> {
    let text = std::str::from_utf8(bytes)
        .map_err(|e| ModelError::new(path, format!("byte {}", e.valid_up_to()), "the file is not UTF-8 text"))?;
    let mut words = text.lines().enumerate().flat_map(|(line, l)| l.split_whitespace().map(move |w| (line + 1, w)));
    let mut last_line = 1;
    let mut next = |what: &str| -> Result<(usize, &str), ModelError> {
        match words.next() {
            Some((line, w)) => {
                last_line = line;
                Ok((line, w))
            }
            None => Err(ModelError::new(
                path,
                format!("line {last_line}"),
                format!("the file ends where {what} should follow (truncated, or a wrong patch count)"),
            )),
        }
    };
    let (line, count) = next("the patch count")?;
    let count: usize = count.parse().ok().filter(|&c| (1..=MAX_PATCHES).contains(&c)).ok_or_else(|| {
        ModelError::new(
            path,
            format!("line {line}"),
            format!("the patch count must be a whole number from 1 to {MAX_PATCHES}"),
        )
    })?;
    let mut patches = Vec::with_capacity(count.min(bytes.len() / 32 + 1));
    for k in 0..count {
        for _ in 0..2 {
            let (line, degree) = next("a patch's degrees")?;
            if degree != "3" {
                return Err(ModelError::new(
                    path,
                    format!("line {line}"),
                    format!(
                        "patch {k} has degree `{}`; only bicubic patches (`3 3`) are read",
                        crate::limits::printable(degree)
                    ),
                ));
            }
        }
        let mut p = [Vec3::ZERO; 16];
        for point in p.iter_mut() {
            let mut c = [0.0f32; 3];
            for v in c.iter_mut() {
                let (line, w) = next("a control point")?;
                let x: f64 = w.parse().map_err(|_| {
                    ModelError::new(
                        path,
                        format!("line {line}"),
                        format!("`{}` is not a number", crate::limits::printable(w)),
                    )
                })?;
                check_number(x, "a control point coordinate")
                    .map_err(|m| ModelError::new(path, format!("line {line}"), m))?;
                *v = x as f32;
            }
            *point = Vec3::from(c);
        }
        patches.push(p);
    }
    let mut mesh = tessellate(&patches, tolerance).map_err(|m| ModelError::new(path, "", m))?;
    mesh.name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    Ok(Model { meshes: vec![mesh], ..Default::default() })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A patch of the plane z = 0 over [0, 3]^2, bent by lifting its middle control points.
    fn bump() -> [Vec3; 16] {
        let mut p = [Vec3::ZERO; 16];
        for j in 0..4 {
            for i in 0..4 {
                let lift = if (1..3).contains(&i) && (1..3).contains(&j) { 1.0 } else { 0.0 };
                p[4 * j + i] = Vec3::new(i as f32, j as f32, lift);
            }
        }
        p
    }

    #[test]
    fn one_wild_control_point_is_an_error_not_millions_of_triangles() {
        let mut wild = bump();
        wild[5].z = 250.0;
        // 32 patches at the finest patch's 256 x 256 steps would be 2 M cells.
        let patches: Vec<[Vec3; 16]> = std::iter::once(wild).chain(std::iter::repeat_n(bump(), 31)).collect();
        let Err(message) = tessellate(&patches, 0.01) else { panic!("2 M cells accepted") };
        assert!(message.contains("raise `flatness`") && message.contains("32 patches"), "{message}");
        // The same patches at a coarser tolerance fit.
        assert!(tessellate(&patches, 1.0).is_ok());
    }

    #[test]
    fn tessellation_stays_within_the_flatness_tolerance() {
        let p = bump();
        for tolerance in [0.1f32, 0.01, 0.001] {
            let n = steps_for(&p, tolerance);
            // Measure the distance from the surface to the bilinear cell at cell centres and
            // edge midpoints, where the interpolation error peaks.
            let mut worst = 0.0f32;
            for j in 0..n {
                for i in 0..n {
                    let (u0, v0, h) = (i as f32 / n as f32, j as f32 / n as f32, 1.0 / n as f32);
                    let corners =
                        [(u0, v0), (u0 + h, v0), (u0, v0 + h), (u0 + h, v0 + h)].map(|(u, v)| evaluate(&p, u, v).0);
                    let mid = evaluate(&p, u0 + h / 2.0, v0 + h / 2.0).0;
                    let bilinear = (corners[0] + corners[1] + corners[2] + corners[3]) / 4.0;
                    worst = worst.max((mid - bilinear).length());
                }
            }
            println!("tolerance {tolerance}: {n} steps, worst deviation {worst}");
            assert!(worst <= tolerance, "tolerance {tolerance}: {worst} with {n} steps");
        }
    }

    #[test]
    fn teapot_file_tessellates_closed_with_outward_normals() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/meshes/teapot.bpt");
        let bytes = std::fs::read(&path).unwrap();
        let model = parse_bpt(&bytes, &path, 0.01).unwrap();
        let mesh = &model.meshes[0];
        assert_eq!(mesh.face_count() % 32, 0);
        // The body's normals point away from the axis at its widest ring (z = 0.9, radius 2).
        let normals = mesh.normals.as_ref().unwrap();
        for (c, &v) in mesh.corners.iter().enumerate() {
            let p = mesh.positions[v as usize];
            // (Away from the handle and spout, which meet the body on the x axis.)
            if (p.z - 0.9).abs() < 1e-4 && (p.truncate().length() - 2.0).abs() < 1e-4 && p.y.abs() > 0.5 {
                let radial = p.truncate().normalize();
                assert!(normals[c].truncate().dot(radial) > 0.99, "{p}: {}", normals[c]);
            }
            assert!(normals[c].is_finite() && normals[c].length() > 0.99, "corner {c} at {p}");
        }
    }

    #[test]
    fn truncated_and_bad_files_are_errors_naming_the_line() {
        let text =
            std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/meshes/teapot.bpt")).unwrap();
        let cut = &text[..text.len() / 2];
        let e = parse_bpt(cut.as_bytes(), Path::new("t.bpt"), 0.01).unwrap_err();
        assert!(e.message.contains("ends"), "{e}");
        let e = parse_bpt(b"1\n3 3\n0 0 nan\n", Path::new("t.bpt"), 0.01).unwrap_err();
        assert_eq!(e.at, "line 3");
        let e = parse_bpt(b"1\n2 2\n", Path::new("t.bpt"), 0.01).unwrap_err();
        assert!(e.message.contains("only bicubic"), "{e}");
    }
}
