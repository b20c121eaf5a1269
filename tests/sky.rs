//! The physical sky, the sun and the rainbow through the whole renderer: a plane lit by sky and
//! sun reflects what the model's irradiances say (the two in one set of units), the sun's place
//! comes from the date, the bows are measured on a rendered image, and bad input is refused.

mod common;

use std::f64::consts::PI;
use std::path::Path;

use glam::{DVec3, Vec3};
use photonix::scene::sky::solar::{sun_position, DateTime};
use photonix::scene::sky::{direction_from_angles, latlong_direction};
use photonix::scene::{parse_scene, LightKind, Scene};

fn parse(text: &str) -> Scene {
    parse_scene(text, Path::new("/tmp/sky-test/scene.toml")).unwrap_or_else(|e| panic!("{e}"))
}

fn parse_err(text: &str) -> String {
    match parse_scene(text, Path::new("/tmp/sky-test/scene.toml")) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// The sun of `scene` (its distant light): direction toward the sun and irradiance.
fn sun(scene: &Scene) -> (Vec3, Vec3) {
    let mut suns = scene.lights.iter().filter_map(|l| match l.kind {
        LightKind::Distant { direction, irradiance, .. } => Some((-direction, irradiance)),
        _ => None,
    });
    let s = suns.next().expect("a sky with a sun above the horizon adds a distant light");
    assert!(suns.next().is_none());
    s
}

const PLANE: &str = r#"
[camera]
type = "orthographic"
position = [0, 5, 0]
look_at = [0, 0, 0]
up = [0, 0, -1]
view_height = 2
resolution = [16, 16]

[photons]
enabled = false

[materials.white]
type = "diffuse"
reflectance = 0.5

[[shapes]]
type = "plane"
normal = [0, 1, 0]
material = "white"
"#;

/// A white plane under the sky and the sun reflects rho / pi times the sun's irradiance times
/// sin(elevation) plus the sky's horizontal irradiance, integrated here from the environment
/// image. Rendering by shadow rays to the distant light and importance-sampled environment
/// samples, on both backends.
#[test]
fn a_plane_under_sky_and_sun_reflects_their_irradiance() {
    let text = format!(
        "{PLANE}\n[render]\nspp = 64\nseed = 2\n\n[environment]\ntype = \"sky\"\nsun_elevation = 35\nsun_azimuth = 120\n"
    );
    let scene = parse(&text);
    let (to_sun, irradiance) = sun(&scene);
    let image = &scene.environment.as_ref().unwrap().image;
    let (w, h) = (image.width, image.height);
    let mut sky = DVec3::ZERO;
    for j in 0..h {
        let (t0, t1) = (PI * j as f64 / h as f64, PI * (j + 1) as f64 / h as f64);
        // Solid angle of a texel times the cosine to +y, exactly over its rows.
        let weight = (2.0 * PI / w as f64) * 0.5 * (t1.sin().powi(2) - t0.sin().powi(2)).max(0.0);
        if t0 >= PI / 2.0 {
            continue;
        }
        for i in 0..w {
            let t = image.texels[(j * w + i) as usize];
            sky += weight * DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64);
        }
    }
    let sun_e = irradiance.as_dvec3() * to_sun.y as f64;
    let expected = 0.5 / PI * (sun_e + sky);
    println!("sun horizontal {sun_e:.4}, sky horizontal {sky:.4}, expected radiance {expected:.5}");
    assert!(sun_e.y > 2.0 * sky.y && sky.z > 0.5 * sun_e.z, "daylight proportions: sun {sun_e}, sky {sky}");
    let buffers = common::buffers(&scene, 16, 16);
    for (backend, img) in
        [("cpu", common::cpu_image(&buffers, 64)), ("gpu", common::gpu_image(&common::gpu(), &buffers, 64))]
    {
        let mut mean = DVec3::ZERO;
        for p in &img.pixels {
            mean += Vec3::from(*p).as_dvec3() / img.pixels.len() as f64;
        }
        let ratio = mean / expected;
        println!("{backend}: rendered {mean:.5}, ratio {ratio:.4}");
        for r in ratio.to_array() {
            assert!((r - 1.0).abs() < 0.02, "{backend}: rendered {mean} against {expected}");
        }
    }
}

/// `latitude`, `longitude`, `date` and `time` put the sun where the solar-position algorithm
/// says, with north along `north`; the sun's colour depends on its elevation alone.
#[test]
fn the_sun_follows_place_date_and_time() {
    let base = format!("{PLANE}\n[environment]\ntype = \"sky\"\nlatitude = 35.68\nlongitude = 139.69\ndate = \"2026-03-20\"\nutc_offset = 9\n");
    let t = |time: &str, north: &str| parse(&format!("{base}time = \"{time}\"\n{north}"));
    let at = |hour: u32| {
        let p = sun_position(
            &DateTime { year: 2026, month: 3, day: 20, hour, minute: 0, second: 0.0, utc_offset_hours: 9.0 },
            35.68,
            139.69,
        );
        direction_from_angles(p.elevation, p.azimuth, Vec3::NEG_Z)
    };
    let (morning, _) = sun(&t("09:00", ""));
    assert!((morning.as_dvec3() - at(9)).length() < 1e-5, "{morning} against {}", at(9));
    // Tokyo in the morning of the equinox: the sun is south-east, so +x (east) and +z (south).
    assert!(morning.x > 0.3 && morning.z > 0.3 && morning.y > 0.3, "{morning}");
    let (afternoon, _) = sun(&t("15:00", ""));
    assert!(afternoon.x < -0.3 && afternoon.z > 0.3, "{afternoon}");
    // North along +x turns the compass a quarter: east becomes +z.
    let (turned, _) = sun(&t("09:00", "north = [1, 0, 0]\n"));
    assert!((turned.x - (-morning.z)).abs() < 1e-5 && (turned.z - morning.x).abs() < 1e-5, "{turned}");
    // At night there is no sun, and a warning says so.
    let night = t("23:00", "");
    assert!(night.lights.is_empty());
    assert!(night.warnings.iter().any(|w| w.contains("below the horizon")), "{:?}", night.warnings);
}

/// The bows measured on a rendered latitude-longitude image: the primary near 42 degrees from
/// the antisolar point with red outside violet, the secondary near 51 with red inside, and
/// Alexander's dark band between them darker than the sky inside the primary.
#[test]
fn rainbow_angles_colours_and_dark_band_on_a_rendered_image() {
    // The sun low in the south (+z), so the antisolar point is 5 degrees below the horizon
    // due north (-z), the middle column of the image.
    let (w, h) = (1440u32, 720u32);
    let text = format!(
        "[camera]\ntype = \"latlong\"\nposition = [0, 0, 0]\nlook_at = [0, 0, -1]\nresolution = [{w}, {h}]\n\n\
         [render]\nspp = 1\n\n[photons]\nenabled = false\n\n\
         [environment]\ntype = \"sky\"\nsun_elevation = 5\nsun_azimuth = 180\nsun = false\n\n[rainbow]\nstrength = 1\n"
    );
    let scene = parse(&text);
    let without = parse(&text.replace("[rainbow]\nstrength = 1\n", ""));
    let buffers = common::buffers(&scene, w, h);
    let img = common::cpu_image(&buffers, 1);
    let sky = common::cpu_image(&common::buffers(&without, w, h), 1);
    // Along the middle column, from the horizon up: angle from the antisolar point = elevation
    // + 5. The bow alone is the image minus the sky without it.
    let column = w / 2;
    let bow = |from_antisolar: f64| -> DVec3 {
        let elevation = from_antisolar - 5.0;
        let row = ((90.0 - elevation) / 180.0 * h as f64) as u32;
        let d = latlong_direction((column as f64 + 0.5) / w as f64, (row as f64 + 0.5) / h as f64);
        assert!(d.z < -0.5, "the middle column looks north");
        let (a, b) = (img.pixel(column, row), sky.pixel(column, row));
        DVec3::new((a[0] - b[0]) as f64, (a[1] - b[1]) as f64, (a[2] - b[2]) as f64)
    };
    let peak = |channel: usize, lo: f64, hi: f64| -> f64 {
        let mut best = (lo, f64::MIN);
        let mut a = lo;
        while a <= hi {
            if bow(a)[channel] > best.1 {
                best = (a, bow(a)[channel]);
            }
            a += 0.25;
        }
        best.0
    };
    let (red1, blue1) = (peak(0, 38.0, 45.0), peak(2, 38.0, 45.0));
    let (red2, blue2) = (peak(0, 48.0, 56.0), peak(2, 48.0, 56.0));
    println!("primary: red {red1}, blue {blue1}; secondary: red {red2}, blue {blue2}");
    assert!((41.0..43.5).contains(&red1) && (39.5..42.0).contains(&blue1), "primary at red {red1}, blue {blue1}");
    assert!(red1 > blue1, "primary: red outside");
    assert!((49.5..52.0).contains(&red2) && (51.5..55.0).contains(&blue2), "secondary at red {red2}, blue {blue2}");
    assert!(red2 < blue2, "secondary: red inside");
    let y = |c: DVec3| 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
    let band = (0..8).map(|k| y(bow(44.5 + 0.5 * k as f64))).sum::<f64>() / 8.0;
    let inside = (0..8).map(|k| y(bow(34.0 + 0.5 * k as f64))).sum::<f64>() / 8.0;
    println!("dark band {band:.4}, inside the primary {inside:.4}, primary peak {:.4}", y(bow(red1)));
    assert!(band < 0.5 * inside, "Alexander's band {band} is not darker than inside the bow {inside}");
    // Below the horizon there is no rain to see.
    assert_eq!(bow(3.0), DVec3::ZERO);
}

/// POV-Ray's drawn rainbow: its colour map spans `width` around `angle` from `direction`.
#[test]
fn pov_rainbow_draws_its_colour_map_across_the_width() {
    let text = "[camera]\ntype = \"latlong\"\nposition = [0, 0, 0]\nlook_at = [0, 0, -1]\nresolution = [720, 360]\n\n\
         [photons]\nenabled = false\n\n[environment]\ntype = \"uniform\"\nradiance = 0.1\n\n\
         [rainbow]\ntype = \"pov\"\ndirection = [0, 0, -1]\nangle = 40\nwidth = 10\nstrength = 1\n\
         colors = [[0, 0, 1], [1, 0, 0]]\n";
    let scene = parse(text);
    let img = common::cpu_image(&common::buffers(&scene, 720, 360), 1);
    // Straight up from the centre (the middle column): 40 degrees from it is elevation 40.
    let at = |elevation: f64| img.pixel(360, ((90.0 - elevation) / 180.0 * 360.0) as u32);
    let (inner, outer, outside) = (at(36.0), at(44.0), at(50.0));
    assert!(inner[2] > inner[0] + 0.3 && outer[0] > outer[2] + 0.3, "inner {inner:?}, outer {outer:?}");
    assert!((outside[0] - 0.1).abs() < 1e-3 && (outside[2] - 0.1).abs() < 1e-3, "outside {outside:?}");
}

#[test]
fn bad_sky_and_rainbow_input_is_refused_with_the_field_named() {
    let sky = |fields: &str| format!("{PLANE}\n[environment]\ntype = \"sky\"\n{fields}");
    for (fields, expected) in [
        ("sun_elevation = 30\nsun_azimuth = 10\nturbidity = 12\n", "`turbidity` is 12"),
        ("sun_elevation = 30\nsun_azimuth = 10\nground_albedo = 1.5\n", "`ground_albedo` is above 1"),
        ("", "a sky needs the sun's place"),
        ("sun_elevation = 30\nsun_azimuth = 10\nsun_direction = [0, 1, 0]\n", "one way only"),
        ("sun_elevation = 30\n", "missing field `sun_azimuth`"),
        ("sun_elevation = 95\nsun_azimuth = 0\n", "-90 to 90"),
        ("latitude = 10\nlongitude = 10\ndate = \"2026-02-30\"\ntime = \"12:00\"\n", "that month has 28 days"),
        ("latitude = 10\nlongitude = 10\ndate = \"2026-02-03\"\ntime = \"25:00\"\n", "past the end of a day"),
        (
            "latitude = 10\nlongitude = 10\ndate = \"2026-02-03\"\ntime = \"12:00\"\nutc_offset = 20\n",
            "`utc_offset` is 20",
        ),
        ("latitude = 100\nlongitude = 10\ndate = \"2026-02-03\"\ntime = \"12:00\"\n", "`latitude` is 100"),
        ("latitude = 10\ndate = \"2026-02-03\"\ntime = \"12:00\"\n", "missing field `longitude`"),
        ("sun_direction = [0, 1, 0]\nrotation = 30\n", "turn the compass with `north"),
        ("sun_direction = [0, 1, 0]\nnorth = [0, 1, 0]\n", "give a horizontal direction"),
        ("sun_direction = [0, 1, 0]\nfile = \"sky.hdr\"\n", "`file` does not apply to a sky"),
    ] {
        let e = parse_err(&sky(fields));
        assert!(e.contains(expected) && e.contains("scene.toml:"), "{fields:?}: {e}");
    }
    let uniform = format!("{PLANE}\n[environment]\ntype = \"uniform\"\nradiance = 1\n");
    for (table, expected) in [
        ("[rainbow]\nstrength = 0.5\n", "needs a sun"),
        ("[rainbow]\ntype = \"pov\"\n", "missing field `direction`"),
        ("[rainbow]\ntype = \"pov\"\ndirection = [0, 0, -1]\narc_angle = 90\nfalloff_angle = 120\n", "falloff <= arc"),
        ("[rainbow]\ntype = \"pov\"\ndirection = [0, 1, 0]\n", "`up` is parallel"),
        ("[rainbow]\ntype = \"pov\"\ndirection = [0, 0, -1]\nstrength = 2\n", "`strength` is 2"),
        ("[rainbow]\ntype = \"pov\"\ndirection = [0, 0, -1]\ncolors = [[1, 0, 0]]\n", "at least 2 colours"),
        ("[rainbow]\ntype = \"rainbow\"\n", "unknown type \"rainbow\""),
    ] {
        let e = parse_err(&format!("{uniform}\n{table}"));
        assert!(e.contains(expected) && e.contains("[rainbow]"), "{table:?}: {e}");
    }
    let e = parse_err(&format!("{PLANE}\n[rainbow]\nstrength = 0.5\n"));
    assert!(e.contains("add an `[environment]`"), "{e}");
}

/// The shipped outdoor scene: the same image from the kernels and the CPU twin.
#[test]
fn gpu_matches_cpu_on_outdoor() {
    let scene = photonix::scene::load_scene(&common::repo_path("scenes/outdoor.toml")).expect("outdoor.toml loads");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let buffers = common::buffers(&scene, 64, 36);
    let photons = common::test_photons();
    let gpu = common::gpu_render(&common::gpu(), &buffers, 2, &photons).image;
    let cpu = common::cpu_render(&buffers, 2, &photons).image;
    let error = photonix::io::metrics::rel_mse(&gpu, &cpu);
    println!("outdoor: gpu vs cpu relMSE {error:.3e}");
    assert!(error < 1e-5, "relMSE {error}");
}
