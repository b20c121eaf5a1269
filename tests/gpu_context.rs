//! The Vulkan backend on whatever device the loader offers (lavapipe in CI), with the validation
//! layer on: every test fails if the layer reports anything it does not expect.

use photonix::gpu::{list_devices, Buffer, GpuContext, GpuError, GpuOptions};

fn gpu() -> GpuContext {
    let options = GpuOptions { device: None, validation: true };
    GpuContext::new(&options).unwrap_or_else(|e| panic!("cannot open the GPU: {e}"))
}

/// xorshift64*: reproducible data without a dependency.
fn random_u32s(n: usize, mut state: u64) -> Vec<u32> {
    (0..n)
        .map(|_| {
            state ^= state >> 12;
            state ^= state << 25;
            state ^= state >> 27;
            (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 32) as u32
        })
        .collect()
}

fn test_add(gpu: &GpuContext) -> photonix::gpu::Kernel {
    let spirv = photonix::shaders::spirv("test_add").expect("build.rs compiles shaders/test_add.comp");
    gpu.create_kernel("test_add", &spirv, 1, 8).expect("test_add matches its declared layout")
}

fn add_push(count: u32, add: u32) -> Vec<u8> {
    bytemuck::cast_slice(&[count, add]).to_vec()
}

fn groups_for(count: u32) -> [u32; 3] {
    [count.div_ceil(photonix::layout::constants::WORKGROUP_SIZE), 1, 1]
}

#[test]
fn context_buffers_and_kernels_are_send_and_sync() {
    fn assert_send_sync<T: Send + Sync>() {}
    assert_send_sync::<GpuContext>();
    assert_send_sync::<Buffer>();
    assert_send_sync::<photonix::gpu::Kernel>();
    assert_send_sync::<GpuError>();
}

#[test]
fn upload_download_round_trips_random_data() {
    let gpu = gpu();
    for staging in [false, true] {
        gpu.set_force_staging(staging);
        for (seed, n) in [0usize, 1, 1000, 1 << 20].into_iter().enumerate() {
            let ints = random_u32s(n, seed as u64 + 1);
            let buffer = gpu.upload("ints", &ints).unwrap();
            assert_eq!(buffer.size(), 4 * n as u64);
            assert_eq!(gpu.download::<u32>(&buffer).unwrap(), ints, "u32, n = {n}, staging {staging}");

            // Any bit pattern is an f32; compare bits so NaNs compare equal too.
            let floats: Vec<f32> = random_u32s(n, seed as u64 + 100).into_iter().map(f32::from_bits).collect();
            let buffer = gpu.upload("floats", &floats).unwrap();
            let back: Vec<f32> = gpu.download(&buffer).unwrap();
            assert!(back.iter().map(|f| f.to_bits()).eq(floats.iter().map(|f| f.to_bits())), "f32, n = {n}");
        }
    }
}

#[test]
fn create_write_and_fill_zero_behave() {
    let gpu = gpu();
    for staging in [false, true] {
        gpu.set_force_staging(staging);
        let buffer = gpu.create_buffer("scratch", 40).unwrap();
        assert_eq!(gpu.download::<u32>(&buffer).unwrap(), vec![0; 10]);
        gpu.write(&buffer, &[7u32, 8, 9]).unwrap();
        assert_eq!(gpu.download::<u32>(&buffer).unwrap(), [7, 8, 9, 0, 0, 0, 0, 0, 0, 0]);
        gpu.fill_zero(&buffer).unwrap();
        assert_eq!(gpu.download::<u32>(&buffer).unwrap(), vec![0; 10]);

        let err = gpu.write(&buffer, &[0u32; 11]).unwrap_err();
        assert!(matches!(err, GpuError::WriteTooLarge { .. }), "{err}");
        let err = gpu.download::<[u8; 3]>(&buffer).unwrap_err();
        assert!(matches!(err, GpuError::ElementSizeMismatch { .. }), "{err}");
    }
}

#[test]
fn batched_dispatches_see_each_others_writes() {
    let gpu = gpu();
    let add = test_add(&gpu);
    let n = 10_000u32;
    let start = random_u32s(n as usize, 7).into_iter().map(|v| v >> 4).collect::<Vec<_>>();
    let values = gpu.upload("values", &start).unwrap();
    let other = gpu.create_buffer("other", u64::from(n) * 4).unwrap();
    gpu.take_timings();
    // Without barriers the three adds would race; with them each sees the previous sum.
    gpu.run("three adds", |r| {
        for k in 1..=3 {
            r.dispatch(&add, &[&values], &add_push(n, k), groups_for(n))?;
        }
        r.copy(&values, &other)?;
        r.dispatch(&add, &[&other], &add_push(n, 100), groups_for(n))?;
        r.fill_zero(&values)
    })
    .unwrap();
    let expected: Vec<u32> = start.iter().map(|v| v + 106).collect();
    assert_eq!(gpu.download::<u32>(&other).unwrap(), expected);
    assert_eq!(gpu.download::<u32>(&values).unwrap(), vec![0; n as usize]);

    let timings = gpu.take_timings();
    if gpu.info().timestamp_period_ns > 0.0 {
        assert_eq!(timings.len(), 1, "{timings:?}");
        let (name, seconds, count) = &timings[0];
        println!("test_add: 4 dispatches of {n} in {:.3} ms", seconds * 1e3);
        assert_eq!((name.as_str(), *count), ("test_add", 4));
        assert!(*seconds >= 0.0 && *seconds < 10.0, "{seconds}");
    }
    assert!(gpu.take_timings().is_empty());
}

#[test]
fn a_failing_recorder_submits_nothing() {
    let gpu = gpu();
    let add = test_add(&gpu);
    let values = gpu.upload("values", &[1u32, 2]).unwrap();
    let err = gpu
        .run("half batch", |r| {
            r.dispatch(&add, &[&values], &add_push(2, 5), [1, 1, 1])?;
            r.dispatch(&add, &[], &add_push(2, 5), [1, 1, 1])
        })
        .unwrap_err();
    assert!(matches!(err, GpuError::BindingCount { given: 0, expected: 1, .. }), "{err}");
    assert!(err.to_string().contains("`test_add`"), "{err}");
    assert_eq!(gpu.download::<u32>(&values).unwrap(), [1, 2]);
}

#[test]
fn dispatch_arguments_are_checked_against_the_kernel_and_device() {
    let gpu = gpu();
    let add = test_add(&gpu);
    let values = gpu.upload("values", &[1u32]).unwrap();
    let err = gpu.run("short push", |r| r.dispatch(&add, &[&values], &[0u8; 4], [1, 1, 1])).unwrap_err();
    assert!(matches!(err, GpuError::PushConstantSize { given: 4, expected: 8, .. }), "{err}");

    let [max_x, _, _] = gpu.info().max_compute_workgroup_count;
    let err = gpu.run("huge", |r| r.dispatch(&add, &[&values], &add_push(1, 1), [max_x + 1, 1, 1])).unwrap_err();
    assert!(matches!(err, GpuError::TooManyGroups { .. }), "{err}");
    println!("{err}");

    let spirv = photonix::shaders::spirv("test_add").unwrap();
    let err = gpu.create_kernel("odd_push", &spirv, 1, 6).unwrap_err();
    assert!(matches!(err, GpuError::PushConstantLimit { .. }), "{err}");
    let err = gpu.create_kernel("garbage", &[1, 2, 3], 1, 8).unwrap_err();
    assert!(matches!(err, GpuError::InvalidSpirv { .. }), "{err}");
}

#[test]
fn buffer_beyond_max_storage_buffer_range_is_refused() {
    let gpu = gpu();
    let limit = gpu.info().max_storage_buffer_range;
    let err = gpu.create_buffer("photons", limit + 1).unwrap_err();
    let message = err.to_string();
    println!("{message}");
    assert!(matches!(err, GpuError::BufferTooLarge { limit_name: "maxStorageBufferRange", .. }));
    assert!(message.contains("`photons`") && message.contains(&limit.to_string()), "{message}");
    // Exactly at the limit is fine (lavapipe: 128 MiB).
    if limit <= 256 << 20 {
        let buffer = gpu.create_buffer("photons", limit).unwrap();
        assert_eq!(buffer.size(), limit);
    }
}

#[test]
fn validation_layer_reports_a_kernel_layout_mismatch() {
    let gpu = gpu();
    let spirv = photonix::shaders::spirv("test_add").unwrap();
    // The shader declares 8 bytes of push constants; a layout without them is invalid, and only
    // the validation layer can tell.
    let err = gpu.create_kernel("test_add_no_push", &spirv, 1, 0).unwrap_err();
    let GpuError::Validation(messages) = &err else { panic!("expected a validation error, got {err}") };
    println!("{err}");
    assert!(!messages.is_empty());
    // The kernel's debug name reaches the message.
    assert!(err.to_string().contains("test_add_no_push"), "{err}");

    // The context stays usable, and the log was cleared by the report.
    let values = gpu.upload("values", &[1u32]).unwrap();
    assert_eq!(gpu.download::<u32>(&values).unwrap(), [1]);
}

#[test]
fn unknown_device_name_lists_the_devices() {
    let devices = list_devices().unwrap();
    assert!(!devices.is_empty());
    let err = GpuContext::new(&GpuOptions { device: Some("no-such-gpu".into()), validation: true }).err().unwrap();
    let message = err.to_string();
    println!("{message}");
    assert!(matches!(err, GpuError::DeviceNotFound { .. }), "{message}");
    for d in &devices {
        assert!(message.contains(&d.name), "{message}");
    }
}

#[test]
fn devices_can_be_chosen_by_index_or_name() {
    let devices = list_devices().unwrap();
    for d in &devices {
        println!("{}", d.describe());
        assert!(d.max_storage_buffer_range > 0 && d.subgroup_size > 0 && d.max_push_constants_size >= 128);
        if d.api_version.starts_with("1.0") || d.api_version.starts_with("1.1") {
            continue;
        }
        let by_index = GpuContext::new(&GpuOptions { device: Some(d.index.to_string()), validation: true }).unwrap();
        assert_eq!(by_index.info(), d);
        drop(by_index);
        let part = d.name.split_whitespace().next().unwrap().to_uppercase();
        let by_name = GpuContext::new(&GpuOptions { device: Some(part), validation: true }).unwrap();
        assert!(by_name.info().name.to_lowercase().contains(&d.name.split_whitespace().next().unwrap().to_lowercase()));
    }
}

#[test]
fn buffers_and_kernels_may_outlive_the_context() {
    let gpu = gpu();
    let buffer: Buffer = gpu.upload("survivor", &[1u32, 2, 3]).unwrap();
    let kernel = test_add(&gpu);
    drop(gpu);
    assert_eq!(buffer.name(), "survivor");
    drop(kernel);
    drop(buffer);
}

#[test]
fn objects_of_another_context_are_refused() {
    let a = gpu();
    let b = gpu();
    let buffer = a.upload("mine", &[1u32]).unwrap();
    let err = b.download::<u32>(&buffer).unwrap_err();
    assert!(matches!(err, GpuError::ForeignObject { .. }), "{err}");
}

/// Runs in a child process with the driver search pointed at a missing file, so the loader finds
/// no driver; the environment of this process stays untouched.
#[test]
fn missing_driver_is_reported() {
    const CHILD: &str = "PHOTONIX_TEST_NO_DRIVER_CHILD";
    if std::env::var_os(CHILD).is_some() {
        let err = GpuContext::new(&GpuOptions::default()).err().expect("no driver is visible");
        assert!(matches!(err, GpuError::NoDriver), "{err}");
        assert_eq!(
            err.to_string(),
            "no Vulkan driver found; install mesa-vulkan-drivers (lavapipe) or use --backend cpu"
        );
        assert!(matches!(list_devices(), Err(GpuError::NoDriver)));
        return;
    }
    let output = std::process::Command::new(std::env::current_exe().unwrap())
        .args(["missing_driver_is_reported", "--exact", "--nocapture", "--test-threads=1"])
        .env(CHILD, "1")
        .env("VK_DRIVER_FILES", "/nonexistent.json")
        .env("VK_ICD_FILENAMES", "/nonexistent.json")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success() && stdout.contains("1 passed"), "child failed:\n{stdout}\n{stderr}");
}
