//! Reconstruction filters (`[render] filter`): the GPU kernels against their CPU twins with a
//! tent and a Gaussian on the integrators that draw camera samples from the filter alone (`pt`,
//! `ppm`) and on those that also spread light-tracing splats by it (`bpt`, `vcm`); and the box,
//! named or not, rendering the images of before filters existed.

mod common;

use photonix::scene::{parse_scene, Scene};

fn scene(integrator: &str, filter: Option<&str>) -> Scene {
    let filter = filter.map_or(String::new(), |f| format!("filter = \"{f}\""));
    let text = format!(
        r#"
[camera]
position = [0, 1, 4]
look_at = [0, 0.5, 0]
fov = 40

[render]
integrator = "{integrator}"
{filter}

[materials.floor]
type = "diffuse"
reflectance = 0.7

[materials.ball]
type = "diffuse"
reflectance = [0.8, 0.3, 0.2]

[[shapes]]
type = "quad"
material = "floor"
vertices = [[-3, 0, 3], [3, 0, 3], [3, 0, -3], [-3, 0, -3]]

[[shapes]]
type = "sphere"
material = "ball"
center = [0, 0.5, 0]
radius = 0.5

[[lights]]
type = "area"
shape = "quad"
vertices = [[-0.5, 2.5, -0.5], [0.5, 2.5, -0.5], [0.5, 2.5, 0.5], [-0.5, 2.5, 0.5]]
radiance = 10
"#
    );
    parse_scene(&text, std::path::Path::new("filters.toml")).expect("the test scene parses")
}

#[test]
fn filters_twins_agree_on_every_integrator() {
    for filter in ["tent", "gaussian"] {
        for integrator in ["ppm", "pt", "bpt", "vcm"] {
            let buffers = common::buffers(&scene(integrator, Some(filter)), 24, 24);
            let out = common::assert_twins_agree(&format!("{filter} filter, {integrator}"), &buffers);
            assert!(out.image.pixels.iter().any(|p| p[0] > 0.0), "{filter}, {integrator}: the image is not black");
        }
    }
}

#[test]
fn stretched_filters_twins_agree() {
    // `filter_radius` stretches the filter on both twins: a box wider than its pixel takes the
    // general splat path, a wide Gaussian's splats reach up to 5 pixels away.
    for (filter, radius, integrator) in [("box", 1.2, "vcm"), ("gaussian", 4.5, "bpt"), ("tent", 0.6, "pt")] {
        let mut scene = scene(integrator, Some(filter));
        scene.render.filter_radius = Some(radius);
        let buffers = common::buffers(&scene, 20, 20);
        common::assert_twins_agree(&format!("{filter} of radius {radius}, {integrator}"), &buffers);
    }
}

#[test]
fn a_named_box_filter_is_the_default_image() {
    for integrator in ["pt", "vcm"] {
        let render = |filter| {
            let buffers = common::buffers(&scene(integrator, filter), 16, 16);
            common::cpu_render(&buffers, 2, &common::test_photons()).image
        };
        let (default, named) = (render(None), render(Some("box")));
        assert_eq!(default.pixels, named.pixels, "{integrator}: box differs from the default");
        let tent = render(Some("tent"));
        assert_ne!(default.pixels, tent.pixels, "{integrator}: the tent changed nothing");
    }
}
