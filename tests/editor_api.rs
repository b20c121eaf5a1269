//! The editor's server through its HTTP and WebSocket API: every edit command, undo and redo,
//! save (comments kept), import, the final render, and the security rules (token, origin, path
//! traversal, symbolic links, size limits).

mod editor_support;

use std::time::{Duration, Instant};

use editor_support::{http, parse, Fixture};
use serde_json::json;

fn ok(r: &editor_support::Response) {
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(r.json()["ok"], true, "{}", r.text());
}

/// The first vertex of an entry's triangles in the page's scene JSON.
fn first_vertex(scene: &serde_json::Value, list: &str, index: usize) -> [f64; 3] {
    let p = &scene[list][index]["positions"];
    [p[0].as_f64().unwrap(), p[1].as_f64().unwrap(), p[2].as_f64().unwrap()]
}

#[test]
fn set_transform_moves_the_shape_and_keeps_comments() {
    let f = Fixture::new();
    let before = first_vertex(&f.scene_json(), "shapes", 1);
    ok(&f.edit(json!({ "op": "set_transform", "target": { "shape": 1 }, "translate": [0.5, 0, -0.25] })));
    let text = f.text();
    assert!(text.contains("transform = { translate = [0.5, 0, -0.25] }"), "{text}");
    assert!(text.contains("# A test scene for the editor."), "{text}");
    let after = first_vertex(&f.scene_json(), "shapes", 1);
    assert!(
        (after[0] - before[0] - 0.5).abs() < 1e-4 && (after[2] - before[2] + 0.25).abs() < 1e-4,
        "{before:?} -> {after:?}"
    );

    // A transform written as a table stays a table; rotate and scale change in place.
    ok(&f.edit(json!({ "op": "set_transform", "target": { "shape": 2 }, "rotate": [0, 45, 0], "scale": [2, 2, 2] })));
    let text = f.text();
    assert!(text.contains("[shapes.transform]\nrotate = [0, 45, 0]\ntranslate = [1, 0, 0]\nscale = 2"), "{text}");
    // The renderer's parse agrees.
    let scene = parse(&text, &f.scene);
    assert_eq!(scene.shapes.len(), 2 + 1 + 12 + 2);

    // An area light has a transform; a point light does not.
    ok(&f.edit(json!({ "op": "set_transform", "target": { "light": 0 }, "translate": [0, 0.5, 0] })));
    let r = f.edit(json!({ "op": "set_transform", "target": { "light": 1 }, "translate": [0, 0.5, 0] }));
    assert_eq!(r.status, 422);
    assert!(r.text().contains("not an area light"), "{}", r.text());
    // A sphere takes only a uniform scale: the parser's own message comes back, nothing changes.
    let text = f.text();
    let r = f.edit(json!({ "op": "set_transform", "target": { "shape": 1 }, "scale": [1, 2, 1] }));
    assert_eq!(r.status, 422, "{}", r.text());
    assert!(r.text().contains("scene.toml:") && r.text().contains("uniform"), "{}", r.text());
    assert_eq!(f.text(), text);
}

#[test]
fn set_changes_material_light_camera_and_render_fields() {
    let f = Fixture::new();
    ok(&f.edit(
        json!({ "op": "set", "target": { "material": "white" }, "field": "reflectance", "value": [0.5, 0.6, 0.7] }),
    ));
    ok(&f.edit(json!({ "op": "set", "target": { "material": "glass" }, "field": "ior", "value": 1.33 })));
    ok(&f.edit(json!({ "op": "set", "target": { "material": "glass" }, "field": "roughness", "value": 0.1 })));
    ok(&f.edit(json!({ "op": "set", "target": { "light": 1 }, "field": "intensity", "value": 3 })));
    ok(&f.edit(json!({ "op": "set", "target": { "light": 0 }, "field": "radiance", "value": [4, 3, 2] })));
    ok(&f.edit(json!({ "op": "set", "target": "camera", "field": "fov", "value": 30 })));
    ok(&f.edit(json!({ "op": "set", "target": "camera", "field": "position", "value": [0, 1.5, 5] })));
    ok(&f.edit(json!({ "op": "set", "target": "render", "field": "spp", "value": 2 })));
    // Several fields in one step: one undo takes them all back.
    let before = f.text();
    ok(&f.edit(
        json!({ "op": "set_fields", "target": "camera", "fields": { "look_at": [0, 0, 0], "up": [0, 1, 0.1] } }),
    ));
    assert!(f.text().contains("look_at = [0, 0, 0]") && f.text().contains("up = [0, 1, 0.1]"), "{}", f.text());
    ok(&f.call("POST", "/api/undo", b""));
    assert_eq!(f.text(), before);
    ok(&f.edit(json!({ "op": "set", "target": { "shape": 0 }, "field": "name", "value": "ground" })));
    let text = f.text();
    // The comment after a replaced value stays with it.
    assert!(text.contains("reflectance = [0.5, 0.6, 0.7]   # grey"), "{text}");
    assert!(text.contains("position = [0, 1.5, 5]   # the eye"), "{text}");
    assert!(text.contains("name = \"ground\"   # the ground"), "{text}");
    let scene = parse(&text, &f.scene);
    assert_eq!(scene.camera.fov_deg, 30.0);
    assert_eq!(scene.render.spp, 2);
    match &scene.materials[2].kind {
        photonix::scene::MaterialKind::Dielectric { ior, roughness } => {
            assert_eq!(*ior, 1.33);
            assert_eq!(roughness.alpha, [0.1, 0.1]);
        }
        other => panic!("{other:?}"),
    }
    // The page's view of the scene follows.
    let page = f.scene_json();
    assert_eq!(page["camera"]["fov"], 30.0);
    assert_eq!(page["materials"][0]["fields"]["reflectance"], json!([0.5, 0.6, 0.7]));
    assert_eq!(page["shapes"][0]["fields"]["name"], "ground");

    // null removes a field; a value the parser refuses changes nothing and says why.
    ok(&f.edit(json!({ "op": "set", "target": { "material": "glass" }, "field": "roughness", "value": null })));
    assert!(!f.text().contains("roughness"));
    let text = f.text();
    for (command, says) in [
        (json!({ "op": "set", "target": { "material": "white" }, "field": "reflectance", "value": 2 }), "reflectance"),
        (json!({ "op": "set", "target": { "material": "white" }, "field": "colour", "value": 1 }), "unknown field"),
        (json!({ "op": "set", "target": { "material": "nope" }, "field": "ior", "value": 1 }), "no material"),
        (json!({ "op": "set", "target": { "shape": 9 }, "field": "name", "value": "x" }), "no shape 9"),
        (json!({ "op": "set", "target": "camera", "field": "fov", "value": "wide" }), "fov"),
        (json!({ "op": "set", "target": "camera", "field": "Bad Key", "value": 1 }), "not a field name"),
        (json!({ "op": "set", "target": { "shape": 0 }, "field": "material", "value": "missing" }), "unknown material"),
    ] {
        let r = f.edit(command.clone());
        assert_eq!(r.status, 422, "{command}: {}", r.text());
        assert!(r.text().contains(says), "{command}: {}", r.text());
        assert_eq!(f.text(), text, "{command} changed the text");
    }
    // Malformed JSON is a 400 with a message.
    let r = f.call("POST", "/api/edit", b"{\"op\":\"set\"");
    assert_eq!(r.status, 400);
    assert!(r.text().contains("malformed edit"), "{}", r.text());
}

#[test]
fn delete_undo_redo_restore_the_text_exactly() {
    let f = Fixture::new();
    let original = f.text();
    ok(&f.edit(json!({ "op": "delete", "target": { "shape": 1 } })));
    assert!(!f.text().contains("name = \"ball\""));
    assert_eq!(f.scene_json()["shapes"].as_array().unwrap().len(), 2);
    ok(&f.edit(json!({ "op": "delete", "target": { "light": 1 } })));
    assert!(!f.text().contains("fill"));
    ok(&f.call("POST", "/api/undo", b""));
    ok(&f.call("POST", "/api/undo", b""));
    assert_eq!(f.text(), original);
    let page = f.scene_json();
    assert_eq!(page["shapes"].as_array().unwrap().len(), 3);
    assert_eq!(page["can_undo"], false);
    assert_eq!(page["can_redo"], true);
    ok(&f.call("POST", "/api/redo", b""));
    assert!(!f.text().contains("name = \"ball\""));
    ok(&f.call("POST", "/api/undo", b""));
    assert_eq!(f.text(), original);
    // Nothing left to undo.
    let r = f.call("POST", "/api/undo", b"");
    assert_eq!(r.status, 422);
    assert!(r.text().contains("nothing to undo"));

    // A material still in use cannot go: the parser names the shape that needs it.
    let r = f.edit(json!({ "op": "delete", "target": { "material": "red" } }));
    assert_eq!(r.status, 422);
    assert!(r.text().contains("unknown material \\\"red\\\"") || r.text().contains("red"), "{}", r.text());
    // An unused one can.
    ok(&f.edit(json!({ "op": "delete", "target": { "material": "glass" } })));
    assert!(!f.text().contains("[materials.glass]"));
    let r = f.edit(json!({ "op": "delete", "target": "camera" }));
    assert_eq!(r.status, 422);
    let r = f.edit(json!({ "op": "delete", "target": { "shape": 7 } }));
    assert_eq!(r.status, 422);
}

#[test]
fn duplicate_and_add_append_entries() {
    let f = Fixture::new();
    ok(&f.edit(json!({ "op": "duplicate", "target": { "shape": 2 } })));
    ok(&f.edit(json!({ "op": "duplicate", "target": { "light": 0 } })));
    ok(&f.edit(json!({ "op": "duplicate", "target": { "material": "red" } })));
    let text = f.text();
    let scene = parse(&text, &f.scene);
    assert!(text.contains("name = \"block copy\""), "{text}");
    assert!(text.contains("[materials.red_copy]"), "{text}");
    // The copy of the turned block has the same transform (as an inline table).
    let page = f.scene_json();
    assert_eq!(page["shapes"].as_array().unwrap().len(), 4);
    assert_eq!(page["shapes"][3]["fields"]["transform"]["rotate"], json!([0, 30, 0]));
    assert_eq!(page["shapes"][3]["positions"], page["shapes"][2]["positions"]);
    assert_eq!(page["lights"].as_array().unwrap().len(), 3);
    assert_eq!(scene.shapes.len(), 2 + 1 + 12 + 12 + 2 + 2);

    ok(&f.edit(json!({ "op": "add", "kind": "shape",
        "table": { "name": "new ball", "type": "sphere", "material": "red_copy", "center": [0, 1, 1], "radius": 0.25 } })));
    ok(&f.edit(json!({ "op": "add", "kind": "light",
        "table": { "type": "spot", "position": [0, 3, 0], "point_at": [0, 0, 0], "intensity": 10, "outer_angle": 30 } })));
    ok(&f.edit(json!({ "op": "add", "kind": "material", "name": "gold", "table": { "type": "conductor", "preset": "gold", "roughness": 0.2 } })));
    let page = f.scene_json();
    assert_eq!(page["shapes"][4]["fields"]["name"], "new ball");
    assert_eq!(page["lights"][3]["kind"], "spot");
    assert_eq!(page["materials"].as_array().unwrap().iter().filter(|m| m["name"] == "gold").count(), 1);
    let text = f.text();
    assert!(text.contains("[materials.gold]"), "{text}");
    // A bad addition is refused whole.
    let r =
        f.edit(json!({ "op": "add", "kind": "shape", "table": { "type": "sphere", "material": "red", "radius": -1 } }));
    assert_eq!(r.status, 422, "{}", r.text());
    let r = f.edit(json!({ "op": "add", "kind": "material", "name": "gold", "table": { "type": "diffuse" } }));
    assert_eq!(r.status, 422);
    assert_eq!(f.text(), text);
}

#[test]
fn save_writes_the_edits_atomically_and_keeps_comments() {
    let f = Fixture::new();
    ok(&f.edit(json!({ "op": "set_transform", "target": { "shape": 1 }, "translate": [0, 0.25, 0] })));
    ok(&f.edit(
        json!({ "op": "set", "target": { "material": "red" }, "field": "reflectance", "value": [0.2, 0.3, 0.4] }),
    ));
    ok(&f.edit(json!({ "op": "delete", "target": { "light": 1 } })));
    assert_eq!(f.scene_json()["dirty"], true);
    // Not yet on disk.
    assert_eq!(std::fs::read_to_string(&f.scene).unwrap(), editor_support::SCENE);
    ok(&f.call("POST", "/api/save", b""));
    assert_eq!(f.scene_json()["dirty"], false);
    let saved = std::fs::read_to_string(&f.scene).unwrap();
    assert_eq!(saved, f.text());
    // Every comment of the original is still there.
    for comment in editor_support::SCENE.lines().filter_map(|l| l.find('#').map(|i| &l[i..])) {
        assert!(saved.contains(comment), "lost {comment:?}:\n{saved}");
    }
    // Reloading gives the edited scene.
    let scene = photonix::scene::load_scene(&f.scene).unwrap();
    assert_eq!(scene.lights.len(), 1);
    let ball = scene.spheres().next().unwrap().0;
    assert!((ball.center.y - 0.75).abs() < 1e-6, "{}", ball.center);
    // No temporary file is left behind.
    let names: Vec<_> = std::fs::read_dir(f.dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(names.len(), 1, "{names:?}");
    // The download is the current text.
    let r = f.call("GET", "/api/scene.toml", b"");
    assert_eq!(r.status, 200);
    assert_eq!(r.text(), saved);
    assert!(r.header("content-disposition").unwrap().contains("scene.toml"));
}

#[test]
fn save_asks_before_replacing_a_file_changed_on_disk() {
    let f = Fixture::new();
    ok(&f.edit(json!({ "op": "set_transform", "target": { "shape": 1 }, "translate": [0, 0.25, 0] })));
    // Another program writes the file meanwhile: a plain save refuses (409) and says so
    let theirs = format!("{}\n# written by another program\n", editor_support::SCENE);
    std::fs::write(&f.scene, &theirs).unwrap();
    let r = f.call("POST", "/api/save", b"");
    assert_eq!(r.status, 409, "{}", r.text());
    let reply = r.json();
    assert_eq!(reply["replace_needed"], true, "{reply}");
    assert!(reply["error"].as_str().unwrap().contains("scene.toml changed on disk"), "{reply}");
    assert_eq!(std::fs::read_to_string(&f.scene).unwrap(), theirs);
    // Told to replace it, it does; then later saves need no question (the file is the editor's)
    ok(&f.call("POST", "/api/save?replace=true", b""));
    assert_eq!(std::fs::read_to_string(&f.scene).unwrap(), f.text());
    ok(&f.edit(json!({ "op": "set_transform", "target": { "shape": 1 }, "translate": [0, 0.5, 0] })));
    ok(&f.call("POST", "/api/save", b""));
    assert_eq!(std::fs::read_to_string(&f.scene).unwrap(), f.text());
}

#[test]
fn serving_a_pov_scene_again_opens_the_newer_toml_saved_beside_it() {
    let dir = tempfile::tempdir().unwrap();
    let pov = dir.path().join("room.pov");
    std::fs::write(&pov, "camera { location <0, 1, -4> look_at 0 }\nlight_source { <2, 4, -3> rgb 1 }\nsphere { 0, 1 pigment { rgb 1 } }\n").unwrap();
    let mut doc = photonix::editor::SceneDocument::load(&pov).unwrap();
    assert_eq!(doc.notice(), None);
    doc.apply(
        &serde_json::from_value(json!({ "op": "set", "target": { "shape": 0 }, "field": "name", "value": "edited" }))
            .unwrap(),
    )
    .unwrap();
    doc.save().unwrap();
    // Opened again: the .toml (newer), with the edit, and a notice naming both files
    let doc = photonix::editor::SceneDocument::load(&pov).unwrap();
    assert_eq!(doc.path(), dir.path().join("room.toml"));
    assert!(doc.text().contains("name = \"edited\""), "{}", doc.text());
    let notice = doc.notice().unwrap();
    assert!(notice.contains("opened room.toml") && notice.contains("room.pov"), "{notice}");
    assert!(!doc.dirty());
    // A broken newer .toml is an error naming it, not a silent translation
    std::fs::write(dir.path().join("room.toml"), "[camera\n").unwrap();
    let e = photonix::editor::SceneDocument::load(&pov).err().unwrap().to_string();
    assert!(e.contains("room.toml beside room.pov is newer") && e.contains("move it away"), "{e}");
}

#[test]
fn requests_without_the_right_token_are_refused() {
    let f = Fixture::new();
    let addr = f.addr();
    for path in ["/", "/app.js", "/api/scene", "/api/scene.toml", "/ws", "/vendor/three.module.min.js"] {
        let r = http(addr, "GET", path, &[], b"");
        assert_eq!(r.status, 401, "{path}: {}", r.text());
        let r = http(addr, "GET", &format!("{path}?token=wrong"), &[], b"");
        assert_eq!(r.status, 403, "{path}: {}", r.text());
        let r = http(addr, "GET", path, &[("Cookie", &format!("photonix_token_{}=nope", addr.port()))], b"");
        assert_eq!(r.status, 403, "{path}");
    }
    let r = http(addr, "POST", "/api/edit", &[], br#"{"op":"delete","target":{"shape":0}}"#);
    assert_eq!(r.status, 401);
    let r = http(addr, "POST", "/api/save?token=x", &[], b"");
    assert_eq!(r.status, 403);
    assert_eq!(f.text(), editor_support::SCENE);

    // The right token works from the query, a header, or the cookie the first visit sets.
    let r = f.call("GET", "/", b"");
    assert_eq!(r.status, 200);
    assert!(r.text().contains("<script type=\"module\""), "{}", r.text());
    let cookie = r.header("set-cookie").expect("a cookie").split(';').next().unwrap().to_string();
    assert!(cookie.contains(&f.token()));
    assert_eq!(r.header("referrer-policy"), Some("no-referrer"));
    assert!(r.header("content-security-policy").unwrap().contains("script-src 'self'"));
    let r = http(addr, "GET", "/app.js", &[("Cookie", &cookie)], b"");
    assert_eq!(r.status, 200);
    let auth = format!("token {}", f.token());
    let r = http(addr, "GET", "/api/scene", &[("Authorization", &auth)], b"");
    assert_eq!(r.status, 200);
    // A page of another origin is refused even with the cookie (the browser would send it).
    let r = http(addr, "POST", "/api/save", &[("Cookie", &cookie), ("Origin", "http://evil.example")], b"");
    assert_eq!(r.status, 403);
    let origin = format!("http://{addr}");
    let r = http(addr, "GET", "/api/scene", &[("Cookie", &cookie), ("Origin", &origin)], b"");
    assert_eq!(r.status, 200);
}

#[test]
fn paths_outside_the_scene_folder_are_refused() {
    let f = Fixture::new();
    let addr = f.addr();
    // No URL reaches a file: the page's files are compiled in.
    for path in ["/../Cargo.toml", "/vendor/../../scene.toml", "/scene.toml", "/%2e%2e/etc/passwd", "//etc/passwd"] {
        let r = http(addr, "GET", &format!("{path}?token={}", f.token()), &[], b"");
        assert!(r.status == 404 || r.status == 400, "{path}: {} {}", r.status, r.text());
        assert!(!r.text().contains("root:"), "{path}");
    }
    // A mesh outside the folder, by `..`, by an absolute path and through a symbolic link.
    let outside = tempfile::tempdir().unwrap();
    let obj = outside.path().join("secret.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    std::os::unix::fs::symlink(&obj, f.dir.path().join("link.obj")).unwrap();
    let relative = format!("../{}/secret.obj", outside.path().file_name().unwrap().to_string_lossy());
    for file in [relative.as_str(), obj.to_str().unwrap(), "link.obj", "/etc/passwd", "missing.obj"] {
        let r = f.edit(
            json!({ "op": "add", "kind": "shape", "table": { "type": "mesh", "material": "white", "file": file } }),
        );
        assert_eq!(r.status, 422, "{file}: {}", r.text());
        let r = f.edit(json!({ "op": "add", "kind": "material", "name": "t", "table": { "type": "diffuse" } }));
        let _ = r;
        let r = f.edit(json!({ "op": "set", "target": "environment", "field": "file", "value": file }));
        assert_eq!(r.status, 422, "{file}: {}", r.text());
    }
    assert!(!f.text().contains("secret"));
    // Imports: the name may not leave the folder.
    for name in ["../x.obj", "..%2Fx.obj", "/tmp/x.obj", ".x.obj", "x.toml"] {
        let r = f.call("POST", &format!("/api/import?name={name}&material=white"), b"v 0 0 0\n");
        assert_eq!(r.status, 400, "{name}: {}", r.text());
    }
    assert!(!f.dir.path().parent().unwrap().join("x.obj").exists());
}

#[test]
fn oversized_requests_are_refused() {
    let f = Fixture::with(photonix::editor::BackendChoice::Cpu, |o| o.max_upload_bytes = 4096);
    let big = vec![b'v'; 8192];
    let r = f.call("POST", "/api/import?name=big.obj&material=white", &big);
    assert_eq!(r.status, 413, "{}", r.text());
    assert!(!f.dir.path().join("big.obj").exists());
    let edit = format!(r#"{{"op":"set","target":"camera","field":"fov","value":"{}"}}"#, "x".repeat(2 << 20));
    let r = f.call("POST", "/api/edit", edit.as_bytes());
    assert_eq!(r.status, 413);
    assert_eq!(f.text(), editor_support::SCENE);
}

#[test]
fn import_adds_a_mesh_shape_and_keeps_the_file_in_the_folder() {
    let f = Fixture::new();
    let obj = "# a tetrahedron\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    let r = f.call("POST", "/api/import?name=tet.obj&material=red", obj.as_bytes());
    ok(&r);
    assert_eq!(r.json()["file"], "tet.obj");
    assert_eq!(std::fs::read_to_string(f.dir.path().join("tet.obj")).unwrap(), obj);
    let page = f.scene_json();
    assert_eq!(page["shapes"][3]["fields"]["file"], "tet.obj");
    assert_eq!(page["shapes"][3]["positions"].as_array().unwrap().len(), 4 * 9);
    // A second import of the same name gets a new name; a broken mesh is refused and removed.
    let r = f.call("POST", "/api/import?name=tet.obj&material=red", obj.as_bytes());
    assert_eq!(r.json()["file"], "tet-2.obj");
    let r = f.call("POST", "/api/import?name=broken.obj&material=red", b"v 0 0\nf 1 2 3\n");
    assert_eq!(r.status, 422, "{}", r.text());
    assert!(r.text().contains("broken.obj"), "{}", r.text());
    assert!(!f.dir.path().join("broken.obj").exists());
    let r = f.call("POST", "/api/import?name=x.obj&material=nope", obj.as_bytes());
    assert_eq!(r.status, 422);
    assert!(!f.dir.path().join("x.obj").exists());
}

#[test]
fn final_render_reports_passes_and_gives_png_and_exr() {
    let f = Fixture::new();
    let r = f.call("GET", "/api/render/image.png", b"");
    assert_eq!(r.status, 404);
    ok(&f.call("POST", "/api/render", br#"{"passes": 3}"#));
    let start = Instant::now();
    let status = loop {
        let s = f.call("GET", "/api/render/status", b"").json();
        if s["state"] == "done" || s["state"] == "failed" {
            break s;
        }
        assert!(start.elapsed() < Duration::from_secs(120), "{s}");
        std::thread::sleep(Duration::from_millis(50));
    };
    assert_eq!(status["state"], "done", "{status}");
    assert_eq!(status["passes"], 3);
    assert_eq!(status["remaining"], 0.0);
    let png = f.call("GET", "/api/render/image.png", b"");
    assert_eq!(png.status, 200);
    assert_eq!(&png.body[..8], b"\x89PNG\r\n\x1a\n");
    let exr = f.call("GET", "/api/render/image.exr", b"");
    assert_eq!(exr.status, 200);
    assert_eq!(&exr.body[..4], &[0x76, 0x2f, 0x31, 0x01]);
    // Its pixels are the render's: the scene's size, and lit.
    let path = f.dir.path().join("out.exr");
    std::fs::write(&path, &exr.body).unwrap();
    let image = photonix::io::read_exr(&path).unwrap();
    assert_eq!((image.width, image.height), (24, 16));
    assert!(image.channel_means()[0] > 0.0);

    // A long render can be cancelled; the passes done are kept.
    ok(&f.call("POST", "/api/render", br#"{"seconds": 600}"#));
    let r = f.call("POST", "/api/render", b"");
    assert_eq!(r.status, 409, "{}", r.text());
    std::thread::sleep(Duration::from_millis(300));
    let s = f.call("GET", "/api/render/status", b"").json();
    assert_eq!(s["state"], "running", "{s}");
    ok(&f.call("POST", "/api/render/cancel", b""));
    let start = Instant::now();
    loop {
        let s = f.call("GET", "/api/render/status", b"").json();
        if s["state"] == "cancelled" {
            break;
        }
        assert!(start.elapsed() < Duration::from_secs(60), "{s}");
        std::thread::sleep(Duration::from_millis(50));
    }
    let r = f.call("POST", "/api/render", br#"{"seconds": -1}"#);
    assert_eq!(r.status, 409);
}

/// A 2 x 2 PNG (opaque, one red texel) at `path`.
fn write_png(path: &std::path::Path) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    let mut image = image::RgbImage::new(2, 2);
    image.put_pixel(0, 0, image::Rgb([255, 0, 0]));
    image.save(path).unwrap();
}

#[test]
fn texture_picker_lists_the_folders_images_and_sets_a_texture_in_one_step() {
    let f = Fixture::new();
    write_png(&f.dir.path().join("textures/wood grain.png"));
    write_png(&f.dir.path().join("rough.png"));
    write_png(&f.dir.path().join(".hidden/x.png"));
    // TGA and GIF load as textures too, so they are listed.
    image::RgbImage::new(2, 2).save(f.dir.path().join("decal.tga")).unwrap();
    image::RgbImage::new(2, 2).save(f.dir.path().join("logo.GIF")).unwrap();
    std::fs::write(f.dir.path().join("notes.txt"), "not an image").unwrap();
    // An image outside the folder, seen through a link inside it, is not listed.
    let outside = tempfile::tempdir().unwrap();
    write_png(&outside.path().join("secret.png"));
    std::os::unix::fs::symlink(outside.path().join("secret.png"), f.dir.path().join("link.png")).unwrap();
    let r = f.call("GET", "/api/images", b"");
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(r.json()["images"], json!(["decal.tga", "logo.GIF", "rough.png", "textures/wood grain.png"]));

    // A colour: sRGB; the texture is named after the file and the field points at it.
    let text = f.text();
    ok(&f.edit(
        json!({ "op": "set_texture", "material": "red", "field": "reflectance", "file": "textures/wood grain.png" }),
    ));
    let after = f.text();
    assert!(after.contains("[textures.wood_grain]\ntype = \"image\"\nfile = \"textures/wood grain.png\""), "{after}");
    assert!(after.contains("reflectance = { texture = \"wood_grain\" }"), "{after}");
    assert!(after.contains("# A test scene for the editor."));
    let scene = parse(&after, &f.scene);
    assert_eq!(scene.textures.len(), 1);
    // The same image again reuses its texture; as data (roughness) it is another one, linear.
    ok(&f.edit(
        json!({ "op": "set_texture", "material": "white", "field": "reflectance", "file": "textures/wood grain.png" }),
    ));
    assert_eq!(f.text().matches("[textures.").count(), 1, "{}", f.text());
    ok(&f.edit(
        json!({ "op": "set_texture", "material": "glass", "field": "roughness", "file": "rough.png", "linear": true }),
    ));
    let t = f.text();
    assert!(t.contains("[textures.rough]\ntype = \"image\"\nfile = \"rough.png\"\ncolor_space = \"linear\""), "{t}");
    assert!(t.contains("roughness = { texture = \"rough\" }"), "{t}");
    // One step each: three undos give the original text back.
    for _ in 0..3 {
        ok(&f.call("POST", "/api/undo", b""));
    }
    assert_eq!(f.text(), text);

    // The server's path rules: outside the folder, through a link out, or missing: refused,
    // nothing changes.
    let escape = format!("../{}/secret.png", outside.path().file_name().unwrap().to_string_lossy());
    for file in [escape.as_str(), outside.path().join("secret.png").to_str().unwrap(), "link.png", "missing.png"] {
        let r = f.edit(json!({ "op": "set_texture", "material": "red", "field": "reflectance", "file": file }));
        assert_eq!(r.status, 422, "{file}: {}", r.text());
        assert_eq!(f.text(), text, "{file}");
    }
    // A field that takes no texture: the parser's message; an unknown material: named.
    let r = f.edit(json!({ "op": "set_texture", "material": "red", "field": "ior", "file": "rough.png" }));
    assert_eq!(r.status, 422, "{}", r.text());
    assert!(r.text().contains("scene.toml:"), "{}", r.text());
    let r = f.edit(json!({ "op": "set_texture", "material": "nope", "field": "reflectance", "file": "rough.png" }));
    assert_eq!(r.status, 422, "{}", r.text());
    assert!(r.text().contains("nope"), "{}", r.text());
    assert_eq!(f.text(), text);
}

/// (min, max) over the vertices of a flat `positions` array.
fn vertex_bounds(positions: &serde_json::Value) -> ([f64; 3], [f64; 3]) {
    let p: Vec<f64> = positions.as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for v in p.chunks_exact(3) {
        for axis in 0..3 {
            lo[axis] = lo[axis].min(v[axis]);
            hi[axis] = hi[axis].max(v[axis]);
        }
    }
    (lo, hi)
}

/// A colour of the page's scene (f32 values) rounded to 4 decimals.
fn rgb(v: &serde_json::Value) -> [f64; 3] {
    [0, 1, 2].map(|i| (v[i].as_f64().unwrap() * 1e4).round() / 1e4)
}

fn near(a: [f64; 3], b: [f64; 3]) -> bool {
    (0..3).all(|i| (a[i] - b[i]).abs() < 1e-4)
}

#[test]
fn instances_are_drawn_listed_and_edited() {
    let f = Fixture::with_text(editor_support::INSTANCES);
    let scene = f.scene_json();
    let instances = scene["instances"].as_array().unwrap();
    let names: Vec<&str> = instances.iter().map(|i| i["fields"]["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["single", "fence", "pairs"]);
    let copies: Vec<u64> = instances.iter().map(|i| i["copies"].as_u64().unwrap()).collect();
    assert_eq!(copies, [1, 6, 2]);
    for i in instances {
        assert_eq!(i["drawn"], "triangles");
        assert_eq!(i["object"], i["fields"]["object"]);
    }

    // One post: a box (12 triangles) and a tessellated ball, in two colours, where the
    // instance puts it.
    let single = &instances[0];
    let triangles = single["positions"].as_array().unwrap().len() / 9;
    assert!(triangles > 12 + 400, "{triangles}");
    let groups = single["groups"].as_array().unwrap();
    assert_eq!(groups.len(), 2, "{groups:?}");
    assert_eq!(rgb(&groups[0]["color"]), [0.7, 0.7, 0.7]);
    assert_eq!(rgb(&groups[1]["color"]), [0.7, 0.1, 0.1]);
    let counts: u64 = groups.iter().map(|g| g["count"].as_u64().unwrap()).sum();
    assert_eq!(counts as usize, triangles);
    assert!(near(vertex_bounds(&single["positions"]).0, [2.9, 0.0, -0.1]), "{:?}", vertex_bounds(&single["positions"]));
    assert!(near(vertex_bounds(&single["positions"]).1, [3.1, 1.2, 0.1]));

    // The grid: six posts in glass (one colour), 0.5 apart along x and 1 along z.
    let fence = &instances[1];
    assert_eq!(fence["positions"].as_array().unwrap().len(), 6 * triangles * 9);
    assert_eq!(fence["groups"].as_array().unwrap().len(), 1);
    let (lo, hi) = vertex_bounds(&fence["positions"]);
    assert!(near(lo, [-1.6, 0.0, -1.6]) && near(hi, [-0.4, 1.2, -0.4]), "{lo:?} {hi:?}");

    // Nested: the pair's two posts at x = +-0.3 in the object, turned a quarter about y (x to
    // -z) and moved to z = 1.5.
    let (lo, hi) = vertex_bounds(&instances[2]["positions"]);
    assert!(near(lo, [-0.1, 0.0, 1.1]) && near(hi, [0.1, 1.2, 1.9]), "{lo:?} {hi:?}");

    // The scene's bounds take the copies in (the lone post sticks out of the floor at x = 3.1).
    assert!((scene["bounds"]["max"][0].as_f64().unwrap() - 3.1).abs() < 1e-5, "{}", scene["bounds"]);

    // An instance's transform is edited as a shape's: the copies move.
    ok(&f.edit(json!({ "op": "set_transform", "target": { "instance": 1 }, "translate": [-1.5, 0.5, -1.5] })));
    assert!(f.text().contains("transform = { translate = [-1.5, 0.5, -1.5] }"), "{}", f.text());
    let (lo, _) = vertex_bounds(&f.scene_json()["instances"][1]["positions"]);
    assert!(near(lo, [-1.6, 0.5, -1.6]), "{lo:?}");
    // A refused value (an unknown object) comes back as the parser's message and changes nothing.
    let text = f.text();
    let r = f.edit(json!({ "op": "set", "target": { "instance": 0 }, "field": "object", "value": "pots" }));
    assert_eq!(r.status, 422, "{}", r.text());
    assert!(r.text().contains("scene.toml:") && r.text().contains("unknown object"), "{}", r.text());
    assert_eq!(f.text(), text);
    let r = f.edit(json!({ "op": "set_transform", "target": { "instance": 3 }, "translate": [0, 0, 0] }));
    assert_eq!(r.status, 422);
    assert!(r.text().contains("there is no instance 3"), "{}", r.text());

    // Duplicate, delete, undo.
    ok(&f.edit(json!({ "op": "duplicate", "target": { "instance": 0 } })));
    let scene = f.scene_json();
    assert_eq!(scene["instances"].as_array().unwrap().len(), 4);
    assert_eq!(scene["instances"][3]["fields"]["name"], "single copy");
    ok(&f.edit(json!({ "op": "delete", "target": { "instance": 1 } })));
    let scene = f.scene_json();
    let names: Vec<&str> =
        scene["instances"].as_array().unwrap().iter().map(|i| i["fields"]["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["single", "pairs", "single copy"]);
    ok(&f.call("POST", "/api/undo", b""));
    assert_eq!(f.scene_json()["instances"][1]["copies"], 6);
}

#[test]
fn a_csg_object_is_drawn_as_its_solids_surface() {
    let f = Fixture::with_text(editor_support::INSTANCES);
    let scene = f.scene_json();
    let cut = &scene["shapes"][3];
    assert_eq!(cut["fields"]["name"], "cut box");
    let p: Vec<f64> = cut["positions"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    assert!(p.len() > 9 * 100, "{}", p.len());
    // Every triangle's centre is on the box minus the ball: inside the box, not inside the ball
    // (the ball's part that shows is the cut, inside the box; the box's part, outside the ball).
    let ball = [0.5, 1.0, 0.5];
    let (mut on_ball, mut on_box) = (0, 0);
    for t in p.chunks_exact(9) {
        let c: Vec<f64> = (0..3).map(|a| (t[a] + t[3 + a] + t[6 + a]) / 3.0).collect();
        let inside_box = (0..3).all(|a| c[a] >= [-0.5, 0.0, -0.5][a] - 1e-4 && c[a] <= [0.5, 1.0, 0.5][a] + 1e-4);
        assert!(inside_box, "a triangle outside the box at {c:?}");
        let r = ((c[0] - ball[0]).powi(2) + (c[1] - ball[1]).powi(2) + (c[2] - ball[2]).powi(2)).sqrt();
        assert!(r > 0.6 * 0.97, "a triangle inside the ball at {c:?} (r = {r})");
        if r < 0.6 * 1.01 {
            on_ball += 1;
        } else {
            on_box += 1;
        }
    }
    assert!(on_ball > 50 && on_box > 50, "{on_ball} {on_box}");
    // Two colours: the box's white, the cut's red.
    let colors: Vec<[f64; 3]> = cut["groups"].as_array().unwrap().iter().map(|g| rgb(&g["color"])).collect();
    assert_eq!(colors, [[0.7, 0.7, 0.7], [0.7, 0.1, 0.1]]);
}

#[test]
fn large_grids_of_instances_are_drawn_as_boxes_then_as_one_box() {
    // 10 000 posts of some 1000 triangles: too many to draw, so each copy is its object's box.
    let f = Fixture::with_text(&editor_support::INSTANCES.replace("count = [3, 1, 2]", "count = [100, 1, 100]"));
    let fence = &f.scene_json()["instances"][1];
    assert_eq!((fence["copies"].as_u64(), fence["drawn"].as_str()), (Some(10_000), Some("boxes")));
    assert_eq!(fence["positions"].as_array().unwrap().len(), 10_000 * 12 * 9);
    let (lo, hi) = vertex_bounds(&fence["positions"]);
    assert!(near(lo, [-1.6, 0.0, -1.6]) && near(hi, [-1.5 + 49.5 + 0.1, 1.2, -1.5 + 99.0 + 0.1]), "{lo:?} {hi:?}");
    // 90 000: twelve triangles each would still be too many; one box around them all.
    let f = Fixture::with_text(&editor_support::INSTANCES.replace("count = [3, 1, 2]", "count = [300, 1, 300]"));
    let fence = &f.scene_json()["instances"][1];
    assert_eq!((fence["copies"].as_u64(), fence["drawn"].as_str()), (Some(90_000), Some("bounds")));
    assert_eq!(fence["positions"].as_array().unwrap().len(), 12 * 9);
    let (lo, hi) = vertex_bounds(&fence["positions"]);
    assert!(near(lo, [-1.6, 0.0, -1.6]) && near(hi, [-1.5 + 149.5 + 0.1, 1.2, -1.5 + 299.0 + 0.1]), "{lo:?} {hi:?}");
}

/// The stable id of entry `index` of `list` in the page's scene.
fn id_of(page: &serde_json::Value, list: &str, index: usize) -> u64 {
    page[list][index]["id"].as_u64().unwrap_or_else(|| panic!("no id on {list}[{index}]: {}", page[list][index]))
}

#[test]
fn stable_ids_name_the_same_entry_after_deletes_undo_and_redo() {
    let f = Fixture::new();
    let page = f.scene_json();
    let (floor, ball, block) = (id_of(&page, "shapes", 0), id_of(&page, "shapes", 1), id_of(&page, "shapes", 2));
    assert!(floor != ball && ball != block);
    // Another tab deletes the floor: the ball is shape 0 now, and its id still names it.
    ok(&f.edit(json!({ "op": "delete", "target": { "shape": 0 } })));
    let page = f.scene_json();
    assert_eq!(id_of(&page, "shapes", 0), ball);
    ok(&f.edit(json!({ "op": "set", "target": { "shape_id": ball }, "field": "radius", "value": 0.25 })));
    let text = f.text();
    let scene = parse(&text, &f.scene);
    assert_eq!(scene.spheres().next().unwrap().0.radius, 0.25);
    // The deleted entry's id names nothing: refused, with a message that says why.
    let r = f.edit(json!({ "op": "set", "target": { "shape_id": floor }, "field": "name", "value": "x" }));
    assert_eq!(r.status, 422, "{}", r.text());
    assert!(r.text().contains("another page may have deleted it"), "{}", r.text());
    // Undo brings the floor back with its id; redo takes it away again.
    ok(&f.call("POST", "/api/undo", b""));
    ok(&f.call("POST", "/api/undo", b""));
    let page = f.scene_json();
    assert_eq!([0, 1, 2].map(|i| id_of(&page, "shapes", i)), [floor, ball, block]);
    ok(&f.call("POST", "/api/redo", b""));
    assert_eq!(id_of(&f.scene_json(), "shapes", 1), block);
    // New entries get new ids.
    ok(&f.edit(json!({ "op": "duplicate", "target": { "shape_id": block } })));
    let page = f.scene_json();
    let copy = id_of(&page, "shapes", 2);
    assert!(![floor, ball, block].contains(&copy), "{copy}");
}

#[test]
fn duplicate_offsets_the_copy_and_batch_is_one_undo_step() {
    let f = Fixture::new();
    let before = f.text();
    // The turned block: the copy's translate moves by the offset, its rotation stays as typed.
    ok(&f.edit(json!({ "op": "duplicate", "target": { "shape": 2 }, "offset": [0.6, 0, 0] })));
    let page = f.scene_json();
    assert_eq!(page["shapes"][3]["fields"]["transform"]["translate"], json!([1.6, 0, 0]));
    assert_eq!(page["shapes"][3]["fields"]["transform"]["rotate"], json!([0, 30, 0]));
    // The ball (no transform): a transform with the offset.
    ok(&f.edit(json!({ "op": "duplicate", "target": { "shape": 1 }, "offset": [1, 0, 0.5] })));
    let page = f.scene_json();
    assert_eq!(page["shapes"][4]["fields"]["transform"], json!({ "translate": [1, 0, 0.5] }));
    let (lo, hi) = vertex_bounds(&page["shapes"][4]["positions"]);
    assert!(
        near([(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, (lo[2] + hi[2]) / 2.0], [1.0, 0.5, 0.5]),
        "{lo:?} {hi:?}"
    );
    // A point light moves its position.
    ok(&f.edit(json!({ "op": "duplicate", "target": { "light": 1 }, "offset": [0, 0, -1] })));
    assert_eq!(f.scene_json()["lights"][2]["fields"]["position"], json!([2, 2, 1]));
    // The steps are the API's (author 0; a page's are its session's), shared by every page.
    assert_eq!(f.scene_json()["undo_author"], 0);
    // Three steps back to the start.
    for _ in 0..3 {
        ok(&f.call("POST", "/api/undo", b""));
    }
    assert_eq!(f.text(), before);
    let page = f.scene_json();
    assert_eq!((page["undo_author"].clone(), page["redo_author"].clone()), (json!(null), json!(0)));

    // A batch (a multi-selection's move) is one step, and all or nothing.
    let page = f.scene_json();
    let (ball, block) = (id_of(&page, "shapes", 1), id_of(&page, "shapes", 2));
    ok(&f.edit(json!({ "op": "batch", "commands": [
        { "op": "set_transform", "target": { "shape_id": ball }, "translate": [0, 1, 0] },
        { "op": "set_transform", "target": { "shape_id": block }, "translate": [1, 1, 0] },
    ] })));
    let text = f.text();
    assert!(text.contains("transform = { translate = [0, 1, 0] }"), "{text}");
    assert!(text.contains("translate = [1, 1, 0]"), "{text}");
    ok(&f.call("POST", "/api/undo", b""));
    assert_eq!(f.text(), before);
    let r = f.edit(json!({ "op": "batch", "commands": [
        { "op": "set_transform", "target": { "shape_id": ball }, "translate": [0, 1, 0] },
        { "op": "set", "target": { "shape_id": block }, "field": "radius", "value": 1 },
    ] }));
    assert_eq!(r.status, 422, "{}", r.text());
    assert_eq!(f.text(), before);
    // Deleting several, highest index first, keeps the ids of the rest.
    let lamp = id_of(&page, "lights", 0);
    ok(&f.edit(json!({ "op": "batch", "commands": [
        { "op": "delete", "target": { "shape_id": block } },
        { "op": "delete", "target": { "shape_id": ball } },
    ] })));
    let page = f.scene_json();
    assert_eq!(page["shapes"].as_array().unwrap().len(), 1);
    assert_eq!(page["shapes"][0]["fields"]["name"], "floor");
    assert_eq!(id_of(&page, "lights", 0), lamp);
    let r = f.edit(json!({ "op": "batch", "commands": [{ "op": "batch", "commands": [] }] }));
    assert_eq!(r.status, 422, "{}", r.text());
}

#[test]
fn groups_are_written_in_the_file_and_checked_by_the_parser() {
    let f = Fixture::new();
    let page = f.scene_json();
    let (ball, block) = (id_of(&page, "shapes", 1), id_of(&page, "shapes", 2));
    ok(&f.edit(json!({ "op": "batch", "commands": [
        { "op": "set", "target": { "shape_id": ball }, "field": "group", "value": "toys" },
        { "op": "set", "target": { "shape_id": block }, "field": "group", "value": "toys" },
        { "op": "set", "target": { "light": 0 }, "field": "group", "value": "toys" },
    ] })));
    let text = f.text();
    assert_eq!(text.matches("group = \"toys\"").count(), 3, "{text}");
    // The renderer reads the same scene with and without the groups.
    let grouped = parse(&text, &f.scene);
    let plain = parse(editor_support::SCENE, &f.scene);
    assert_eq!(grouped.shapes.len(), plain.shapes.len());
    assert_eq!(f.scene_json()["shapes"][1]["fields"]["group"], "toys");
    // An empty name, and a group inside a csg or an object, are refused with file:line:column.
    let r = f.edit(json!({ "op": "set", "target": { "shape_id": ball }, "field": "group", "value": "" }));
    assert_eq!(r.status, 422, "{}", r.text());
    assert!(r.text().contains("`group` is a name of 1 to 64 characters"), "{}", r.text());
    let bad = format!(
        "{}\n[[shapes]]\ntype = \"csg\"\noperation = \"union\"\nmaterial = \"red\"\nchildren = [{{ type = \"sphere\", center = [0, 0, 0], radius = 1, group = \"g\" }}, {{ type = \"sphere\", center = [1, 0, 0], radius = 1 }}]\n",
        editor_support::SCENE
    );
    let e = photonix::scene::parse_scene(&bad, &f.scene).unwrap_err().to_string();
    assert!(e.contains("scene.toml:") && e.contains("`group` applies only to top-level"), "{e}");
    let line = bad.lines().position(|l| l.starts_with("children")).unwrap() + 1;
    assert!(e.contains(&format!(":{line}:")), "{e}");
    let bad = format!("{}{}", editor_support::SCENE, "\n[[objects.o.shapes]]\ntype = \"sphere\"\nmaterial = \"red\"\ncenter = [0, 0, 0]\nradius = 1\ngroup = \"g\"\n\n[[instances]]\nobject = \"o\"\ngroup = \"ok\"\n");
    let e = photonix::scene::parse_scene(&bad, &f.scene).unwrap_err().to_string();
    assert!(e.contains("`group` applies only to top-level"), "{e}");
}

#[test]
fn import_takes_every_model_format_and_centres_it_where_asked() {
    let f = Fixture::new();
    let models = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/models/assimp");
    let glb =
        std::fs::read(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/meshes/rounded-cube.glb")).unwrap();
    let ply = std::fs::read(models.join("cube.ply")).unwrap();
    let tds = std::fs::read(models.join("test1.3ds")).unwrap();
    let before = f.text();
    for (name, bytes, at) in
        [("cube.glb", &glb, [1.0, 2.0, 3.0]), ("cube.ply", &ply, [-1.0, 0.5, 0.0]), ("t.3ds", &tds, [0.0, 0.0, -2.0])]
    {
        let r = f.call("POST", &format!("/api/import?name={name}&at={},{},{}", at[0], at[1], at[2]), bytes);
        ok(&r);
        let page = f.scene_json();
        let shapes = page["shapes"].as_array().unwrap();
        let last = shapes.last().unwrap();
        assert_eq!(last["fields"]["file"], name, "{name}");
        assert!(last["fields"].get("material").is_none(), "the file's own materials: {}", last["fields"]);
        let (lo, hi) = vertex_bounds(&last["positions"]);
        let centre = [0, 1, 2].map(|i| (lo[i] + hi[i]) / 2.0);
        let size = (0..3).map(|i| hi[i] - lo[i]).fold(0.0, f64::max);
        assert!(
            (0..3).all(|i| (centre[i] - at[i]).abs() < 1e-3 * size.max(1.0)),
            "{name}: centre {centre:?}, asked {at:?}"
        );
    }
    // Each import is one undo step (the placement included).
    for _ in 0..3 {
        ok(&f.call("POST", "/api/undo", b""));
    }
    assert_eq!(f.text(), before);
    let r = f.call("POST", "/api/import?name=x.png", b"x");
    assert_eq!(r.status, 400);
    assert!(r.text().contains(".obj, .gltf, .glb, .ply, .3ds, .ifs, .bpt"), "{}", r.text());
    let r = f.call("POST", "/api/import?name=x.ply&at=1,2", &ply);
    assert_eq!(r.status, 400);
    assert!(r.text().contains("three finite numbers"), "{}", r.text());
}

#[test]
fn a_given_token_is_used_and_a_bad_one_refused() {
    let f = Fixture::with(photonix::editor::BackendChoice::Cpu, |o| o.token = Some("restart-me_0123456789".into()));
    assert_eq!(f.token(), "restart-me_0123456789");
    ok(&f.edit(json!({ "op": "set", "target": { "shape": 1 }, "field": "radius", "value": 0.3 })));
    let runtime = tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap();
    for bad in ["short", "has space in it 0123456789", "ünïcode-0123456789"] {
        let mut options = photonix::editor::ServeOptions::new(f.scene.clone());
        options.token = Some(bad.into());
        let e = runtime.block_on(photonix::editor::Server::start(options)).err().expect("refused").to_string();
        assert!(e.contains("--token takes 16 to 128 letters"), "{e}");
    }
}

/// `photonix serve` as a user runs it: the first Ctrl-C (SIGINT) with unsaved edits only warns,
/// a second stops it; and it prints how to restart it so that open pages reconnect.
#[test]
fn serve_warns_on_ctrl_c_while_edits_are_unsaved() {
    use std::io::{BufRead, BufReader};
    use std::process::{Command, Stdio};
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.toml");
    std::fs::write(&scene, editor_support::SCENE).unwrap();
    let token = "ctrl-c-test-token-0123456789";
    let mut child = Command::new(env!("CARGO_BIN_EXE_photonix"))
        .args(["serve", scene.to_str().unwrap(), "--backend", "cpu", "--preview-size", "16", "--token", token])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start photonix serve");
    let stdout = BufReader::new(child.stdout.take().unwrap());
    let (tx, rx) = std::sync::mpsc::channel::<String>();
    let stderr = child.stderr.take().unwrap();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            let _ = tx.send(line);
        }
    });
    let url = stdout.lines().map_while(Result::ok).find(|l| l.contains("token=")).expect("the URL");
    let port: u16 = url.split(':').nth(2).unwrap().split('/').next().unwrap().parse().unwrap();
    let addr: std::net::SocketAddr = format!("127.0.0.1:{port}").parse().unwrap();
    let wait_for = |what: &str| -> Vec<String> {
        let mut seen = Vec::new();
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(30) {
            if let Ok(line) = rx.recv_timeout(Duration::from_millis(100)) {
                let hit = line.contains(what);
                seen.push(line);
                if hit {
                    return seen;
                }
            }
        }
        panic!("no \"{what}\" on stderr: {seen:?}");
    };
    let lines = wait_for("Ctrl-C stops the server");
    assert!(lines.iter().any(|l| l.contains(&format!("restart with --port {port} --token {token}"))), "{lines:?}");
    let edit = json!({ "op": "set", "target": { "shape": 1 }, "field": "radius", "value": 0.3 }).to_string();
    let r = http(addr, "POST", &format!("/api/edit?token={token}"), &[], edit.as_bytes());
    assert_eq!(r.status, 200, "{}", r.text());
    let interrupt = |pid: u32| {
        assert!(Command::new("kill").args(["-INT", &pid.to_string()]).status().unwrap().success());
    };
    interrupt(child.id());
    let lines = wait_for("unsaved edits");
    assert!(lines.iter().any(|l| l.contains("press Ctrl-C again within 10 s")), "{lines:?}");
    std::thread::sleep(Duration::from_millis(300));
    assert!(child.try_wait().unwrap().is_none(), "the first Ctrl-C stopped the server");
    interrupt(child.id());
    wait_for("the unsaved edits are dropped");
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        assert!(start.elapsed() < Duration::from_secs(20), "the second Ctrl-C did not stop the server");
        std::thread::sleep(Duration::from_millis(50));
    }
    assert_eq!(std::fs::read_to_string(&scene).unwrap(), editor_support::SCENE, "nothing was saved");
}

#[test]
fn kinds_are_served_as_the_format_declares_them() {
    // The materials panel shows these fields and defaults; they are the parser's own.
    let f = Fixture::new();
    let r = f.call("GET", "/api/kinds", b"");
    assert_eq!(r.status, 200, "{}", r.text());
    let kinds = r.json();
    let diffuse = kinds["materials"]["diffuse"].as_array().unwrap();
    let reflectance = diffuse.iter().find(|f| f["name"] == "reflectance").unwrap();
    let photonix::scene::kinds::Default::Triple(declared) = photonix::scene::kinds::REFLECTANCE.default else {
        panic!("reflectance has a three-number default")
    };
    assert_eq!(reflectance["default"], json!(declared));
    assert_eq!(reflectance["type"], "color or texture");
    assert_eq!(reflectance["shared"], false);
    let names: Vec<&str> = diffuse.iter().map(|f| f["name"].as_str().unwrap()).collect();
    assert_eq!(names, photonix::scene::kinds::MATERIALS.kind("diffuse").field_names());
    let preset = kinds["materials"]["conductor"].as_array().unwrap().iter().find(|f| f["name"] == "preset").unwrap();
    assert!(preset["choices"].as_array().unwrap().contains(&json!("gold")));
    assert!(
        kinds["shapes"]["torus"].is_array()
            && kinds["lights"]["spot"].is_array()
            && kinds["media"]["heterogeneous"].is_array()
    );
    // The page imports the same as a module.
    let module = f.call("GET", "/kinds.js", b"");
    assert_eq!(module.status, 200);
    assert_eq!(module.header("content-type"), Some("text/javascript; charset=utf-8"));
    assert_eq!(module.text(), format!("export const KINDS = {kinds};\n"));
}
