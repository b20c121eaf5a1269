//! Intel Open Image Denoise (OIDN 2.x), loaded at run time with `libloading`: a render without
//! `--denoise` needs no library, and a missing one is a clear error naming what to install.
//! (Here, beside the Vulkan code, because it is the other foreign library we call: `unsafe`
//! lives only in src/gpu/.)
//!
//! The few C functions used are declared from OIDN 2.5's `include/OpenImageDenoise/oidn.h`:
//! device, buffers, the "RT" filter with `hdr` and `cleanAux`, its progress monitor (to cancel),
//! errors and releases.
//!
//! Where the library is looked for, first found wins (see docs/denoising.md):
//! 1. `PHOTONIX_OIDN`: the library file, or a folder holding it (alone: nothing else is tried,
//!    so a wrong value is an error rather than a silent fallback);
//! 2. `OIDN_DIR`: an OIDN install (its `lib/`), as the `oidn` crate reads it;
//! 3. where `ci/setup` installs PyPI's `pyoidn` wheel: `target/oidn/pyoidn/oidn/lib` beside the
//!    executable's `target/` folder, and in the source tree it was built from;
//! 4. the system loader's path (`libOpenImageDenoise.so.2`, e.g. from a distribution package).

use std::ffi::{c_char, c_void, CStr};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// The library's file name (the 2.x ABI).
pub const LIBRARY: &str = if cfg!(target_os = "windows") {
    "OpenImageDenoise.dll"
} else if cfg!(target_os = "macos") {
    "libOpenImageDenoise.2.dylib"
} else {
    "libOpenImageDenoise.so.2"
};

/// What to tell a user without the library.
pub const INSTALL_HINT: &str =
    "install Open Image Denoise 2.x: `pip install pyoidn==2.5.1.0` and set PHOTONIX_OIDN to \
     its pyoidn/oidn/lib folder, or run ci/setup (it installs the wheel into target/oidn), or set OIDN_DIR to an OIDN \
     release; see docs/denoising.md";

#[derive(Debug, thiserror::Error)]
pub enum DenoiseError {
    #[error("Open Image Denoise ({LIBRARY}) was not found: {looked}; {INSTALL_HINT}")]
    NotFound { looked: String },
    #[error("Open Image Denoise at {path} could not be loaded: {reason}; {INSTALL_HINT}")]
    Load { path: String, reason: String },
    #[error("Open Image Denoise: {what} failed: {message}")]
    Device { what: &'static str, message: String },
    #[error("the denoise was cancelled")]
    Cancelled,
    #[error("denoise: the {name} image is {got} pixels, the color image {want}")]
    Size { name: &'static str, got: usize, want: usize },
}

/// OIDN's device types (`OIDNDeviceType`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeviceType {
    Cpu,
    Cuda,
}

impl DeviceType {
    fn code(self) -> i32 {
        match self {
            DeviceType::Cpu => 1,  // OIDN_DEVICE_TYPE_CPU
            DeviceType::Cuda => 3, // OIDN_DEVICE_TYPE_CUDA
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            DeviceType::Cpu => "CPU",
            DeviceType::Cuda => "CUDA",
        }
    }
}

type Handle = *mut c_void;
const OIDN_FORMAT_FLOAT3: i32 = 3;

/// The C functions used, resolved once from the library.
struct Api {
    new_device: unsafe extern "C" fn(i32) -> Handle,
    commit_device: unsafe extern "C" fn(Handle),
    release_device: unsafe extern "C" fn(Handle),
    get_device_error: unsafe extern "C" fn(Handle, *mut *const c_char) -> i32,
    new_buffer: unsafe extern "C" fn(Handle, usize) -> Handle,
    write_buffer: unsafe extern "C" fn(Handle, usize, usize, *const c_void),
    read_buffer: unsafe extern "C" fn(Handle, usize, usize, *mut c_void),
    release_buffer: unsafe extern "C" fn(Handle),
    new_filter: unsafe extern "C" fn(Handle, *const c_char) -> Handle,
    set_filter_image: unsafe extern "C" fn(Handle, *const c_char, Handle, i32, usize, usize, usize, usize, usize),
    set_filter_bool: unsafe extern "C" fn(Handle, *const c_char, bool),
    set_progress_monitor: unsafe extern "C" fn(Handle, Option<Monitor>, *mut c_void),
    commit_filter: unsafe extern "C" fn(Handle),
    execute_filter: unsafe extern "C" fn(Handle),
    release_filter: unsafe extern "C" fn(Handle),
    /// Kept loaded while the pointers above are used.
    _library: libloading::Library,
}

/// The places to look for the library, in order, and whether the system loader is tried last.
fn candidates() -> (Vec<PathBuf>, bool) {
    let in_folder =
        |dir: &Path| vec![dir.join(LIBRARY), dir.join("lib").join(LIBRARY), dir.join("pyoidn/oidn/lib").join(LIBRARY)];
    let file_or_folder = |p: PathBuf| if p.is_dir() { in_folder(&p) } else { vec![p] };
    if let Some(p) = std::env::var_os("PHOTONIX_OIDN").filter(|p| !p.is_empty()) {
        return (file_or_folder(PathBuf::from(p)), false);
    }
    let mut out = Vec::new();
    if let Some(p) = std::env::var_os("OIDN_DIR").filter(|p| !p.is_empty()) {
        out.extend(file_or_folder(PathBuf::from(p)));
    }
    // target/release/photonix (or target/release/deps/test-…) -> target/oidn.
    if let Ok(exe) = std::env::current_exe() {
        for target in exe.ancestors().skip(1).take(3).filter(|a| a.file_name().is_some_and(|n| n == "target")) {
            out.extend(in_folder(&target.join("oidn")));
        }
    }
    out.extend(in_folder(&Path::new(env!("CARGO_MANIFEST_DIR")).join("target/oidn")));
    // The executable's target/ is usually the source tree's: each place once, in its first turn.
    let mut seen = std::collections::HashSet::new();
    out.retain(|p| seen.insert(p.clone()));
    (out, true)
}

impl Api {
    fn load() -> Result<Api, DenoiseError> {
        let (paths, system) = candidates();
        let mut looked = Vec::new();
        let mut library = None;
        for path in &paths {
            if !path.is_file() {
                looked.push(path.display().to_string());
                continue;
            }
            // SAFETY: loading OIDN runs its initialisers, which have no preconditions.
            match unsafe { libloading::Library::new(path) } {
                Ok(l) => {
                    library = Some((l, path.display().to_string()));
                    break;
                }
                Err(e) => return Err(DenoiseError::Load { path: path.display().to_string(), reason: e.to_string() }),
            }
        }
        if library.is_none() && system {
            // SAFETY: as above, by name through the system loader's path.
            match unsafe { libloading::Library::new(LIBRARY) } {
                Ok(l) => library = Some((l, LIBRARY.to_string())),
                Err(_) => looked.push(format!("the system loader's path ({LIBRARY})")),
            }
        }
        let Some((library, path)) = library else {
            let source = if system { "" } else { "PHOTONIX_OIDN: " };
            return Err(DenoiseError::NotFound { looked: format!("looked in {source}{}", looked.join(", ")) });
        };
        let missing = |e: libloading::Error| DenoiseError::Load { path: path.clone(), reason: e.to_string() };
        // SAFETY: each symbol is declared with the signature oidn.h 2.x gives it.
        unsafe {
            Ok(Api {
                new_device: *library.get(b"oidnNewDevice\0").map_err(missing)?,
                commit_device: *library.get(b"oidnCommitDevice\0").map_err(missing)?,
                release_device: *library.get(b"oidnReleaseDevice\0").map_err(missing)?,
                get_device_error: *library.get(b"oidnGetDeviceError\0").map_err(missing)?,
                new_buffer: *library.get(b"oidnNewBuffer\0").map_err(missing)?,
                write_buffer: *library.get(b"oidnWriteBuffer\0").map_err(missing)?,
                read_buffer: *library.get(b"oidnReadBuffer\0").map_err(missing)?,
                release_buffer: *library.get(b"oidnReleaseBuffer\0").map_err(missing)?,
                new_filter: *library.get(b"oidnNewFilter\0").map_err(missing)?,
                set_filter_image: *library.get(b"oidnSetFilterImage\0").map_err(missing)?,
                set_filter_bool: *library.get(b"oidnSetFilterBool\0").map_err(missing)?,
                set_progress_monitor: *library.get(b"oidnSetFilterProgressMonitorFunction\0").map_err(missing)?,
                commit_filter: *library.get(b"oidnCommitFilter\0").map_err(missing)?,
                execute_filter: *library.get(b"oidnExecuteFilter\0").map_err(missing)?,
                release_filter: *library.get(b"oidnReleaseFilter\0").map_err(missing)?,
                _library: library,
            })
        }
    }
}

/// Whether the library can be loaded, and if not why (the editor's toggle says so).
pub fn available() -> Result<(), DenoiseError> {
    Api::load().map(drop)
}

/// An OIDN device with its library: made once, used for many images (the editor's preview).
pub struct Denoiser {
    api: Api,
    device: Handle,
    device_type: DeviceType,
    /// The filters of the last image size, kept for the next image of that size.
    cache: Option<Cache>,
    /// Cancels a running denoise when set (`set_stop_flag`).
    stop: Option<Arc<AtomicBool>>,
}

// SAFETY: OIDN devices and their objects may be used from any thread, one call at a time
// (oidn.h: "thread-safe ... unless noted"); `Denoiser` is used through `&mut self`.
unsafe impl Send for Denoiser {}

impl Denoiser {
    /// Loads the library and opens a device of `device_type`.
    pub fn new(device_type: DeviceType) -> Result<Denoiser, DenoiseError> {
        let api = Api::load()?;
        // SAFETY: the functions come from the loaded library; the device is checked below.
        let device = unsafe { (api.new_device)(device_type.code()) };
        if device.is_null() {
            return Err(DenoiseError::Device {
                what: "creating the device",
                message: format!("no {} device", device_type.name()),
            });
        }
        let mut denoiser = Denoiser { api, device, device_type, cache: None, stop: None };
        // SAFETY: a device just created.
        unsafe { (denoiser.api.commit_device)(denoiser.device) };
        denoiser.check("opening the device")?;
        Ok(denoiser)
    }

    /// A CUDA device where `prefer_cuda` (the renderer runs on an NVIDIA GPU) and one opens,
    /// else the CPU device.
    pub fn open(prefer_cuda: bool) -> Result<Denoiser, DenoiseError> {
        if prefer_cuda {
            if let Ok(d) = Denoiser::new(DeviceType::Cuda) {
                return Ok(d);
            }
        }
        Denoiser::new(DeviceType::Cpu)
    }

    pub fn device_type(&self) -> DeviceType {
        self.device_type
    }

    fn check(&mut self, what: &'static str) -> Result<(), DenoiseError> {
        let mut message: *const c_char = std::ptr::null();
        // SAFETY: a live device; the message, when set, is a C string OIDN owns until its next call.
        let code = unsafe { (self.api.get_device_error)(self.device, &mut message) };
        if code == 0 {
            return Ok(());
        }
        let text = if message.is_null() {
            format!("error code {code}")
        } else {
            // SAFETY: non-null, NUL-terminated, valid until the next OIDN call.
            unsafe { CStr::from_ptr(message) }.to_string_lossy().into_owned()
        };
        Err(DenoiseError::Device { what, message: text })
    }

    /// Makes a running denoise stop (with [`DenoiseError::Cancelled`]) soon after `flag` is set,
    /// through OIDN's progress monitor: the editor drops a stale preview's denoise.
    pub fn set_stop_flag(&mut self, flag: Option<Arc<AtomicBool>>) {
        self.stop = flag;
        self.release_filters();
    }

    fn release_filters(&mut self) {
        if let Some(cache) = self.cache.take() {
            // SAFETY: objects created by `prepare`, released once.
            unsafe {
                for f in cache.filters {
                    (self.api.release_filter)(f);
                }
                for b in cache.buffers {
                    (self.api.release_buffer)(b);
                }
            }
        }
    }

    /// The filters and buffers of a `width` x `height` denoise, made and committed once per size
    /// (committing an RT filter builds its network and scratch memory: most of a small image's
    /// time), then reused: the editor's preview denoises many frames of one size.
    fn prepare(&mut self, width: usize, height: usize, guided: bool) -> Result<(), DenoiseError> {
        if self.cache.as_ref().is_some_and(|c| (c.width, c.height, c.guided) == (width, height, guided)) {
            return Ok(());
        }
        self.release_filters();
        let bytes = width * height * 12;
        let mut cache = Cache { width, height, guided, buffers: Vec::new(), filters: Vec::new() };
        let monitor: Option<Monitor> = self.stop.as_ref().map(|_| monitor as Monitor);
        let user = self.stop.as_ref().map_or(std::ptr::null_mut(), |f| Arc::as_ptr(f) as *mut c_void);
        // SAFETY: a live device; every buffer holds width x height float triples; the monitor's
        // user pointer is the AtomicBool `self.stop` keeps alive while the filters live (a new
        // flag releases them first).
        let made = unsafe {
            // Buffers: color, output, then albedo, normal and their prefiltered copies.
            for _ in 0..if guided { 6 } else { 2 } {
                cache.buffers.push((self.api.new_buffer)(self.device, bytes));
            }
            let b = cache.buffers.clone();
            let mut filter = |inputs: &[(&CStr, Handle)], output: Handle, hdr: bool, clean_aux: bool| {
                let f = (self.api.new_filter)(self.device, c"RT".as_ptr());
                cache.filters.push(f);
                for (name, buffer) in inputs.iter().chain([&(c"output", output)]) {
                    (self.api.set_filter_image)(f, name.as_ptr(), *buffer, OIDN_FORMAT_FLOAT3, width, height, 0, 0, 0);
                }
                (self.api.set_filter_bool)(f, c"hdr".as_ptr(), hdr);
                (self.api.set_filter_bool)(f, c"cleanAux".as_ptr(), clean_aux);
                (self.api.set_progress_monitor)(f, monitor, user);
                (self.api.commit_filter)(f);
            };
            if guided {
                // Prefilter the guides (OIDN 2.x takes each as the "albedo" or "normal" input of
                // an RT filter with no colour), then the colour with them, as clean.
                filter(&[(c"albedo", b[2])], b[4], false, false);
                filter(&[(c"normal", b[3])], b[5], false, false);
                filter(&[(c"color", b[0]), (c"albedo", b[4]), (c"normal", b[5])], b[1], true, true);
            } else {
                filter(&[(c"color", b[0])], b[1], true, false);
            }
            self.cache = Some(cache);
            self.check("setting up the RT filters")
        };
        if made.is_err() {
            self.release_filters();
        }
        made
    }

    /// Denoises `color` (HDR radiance, row by row) with OIDN's "RT" filter, guided by `albedo`
    /// and `normal` where given; the guides are first denoised with RT filters of their own and
    /// then passed as clean (`cleanAux`), as OIDN's documentation recommends for noisy guides.
    pub fn denoise(
        &mut self,
        width: u32,
        height: u32,
        color: &[[f32; 3]],
        guides: Option<Guides>,
    ) -> Result<Vec<[f32; 3]>, DenoiseError> {
        let (w, h) = (width as usize, height as usize);
        let want = w * h;
        let sized = |name: &'static str, image: &[[f32; 3]]| {
            if image.len() == want {
                Ok(())
            } else {
                Err(DenoiseError::Size { name, got: image.len(), want })
            }
        };
        sized("color", color)?;
        if let Some((albedo, normal)) = guides {
            sized("albedo", albedo)?;
            sized("normal", normal)?;
        }
        self.prepare(w, h, guides.is_some())?;
        let cache = self.cache.as_ref().expect("prepared just above");
        let bytes = want * 12;
        let mut out = vec![[0.0f32; 3]; want];
        // SAFETY: the buffers hold `bytes` each, written from and read into slices of that size;
        // the filters were committed on them by `prepare`.
        unsafe {
            (self.api.write_buffer)(cache.buffers[0], 0, bytes, color.as_ptr().cast());
            if let Some((albedo, normal)) = guides {
                (self.api.write_buffer)(cache.buffers[2], 0, bytes, albedo.as_ptr().cast());
                (self.api.write_buffer)(cache.buffers[3], 0, bytes, normal.as_ptr().cast());
            }
            for &f in &cache.filters {
                (self.api.execute_filter)(f);
                let mut message: *const c_char = std::ptr::null();
                let code = (self.api.get_device_error)(self.device, &mut message);
                // The monitor said stop: whatever OIDN reports then, it is the cancel asked for.
                let stopped = self.stop.as_ref().is_some_and(|f| f.load(Ordering::Relaxed))
                    || crate::render::STOP.load(Ordering::Relaxed);
                if code == OIDN_ERROR_CANCELLED || (code != 0 && stopped) {
                    return Err(DenoiseError::Cancelled);
                }
                if !message.is_null() {
                    let text = CStr::from_ptr(message).to_string_lossy().into_owned();
                    return Err(DenoiseError::Device { what: "running the RT filter", message: text });
                }
            }
            (self.api.read_buffer)(cache.buffers[1], 0, bytes, out.as_mut_ptr().cast());
        }
        self.check("reading the result")?;
        Ok(out)
    }
}

/// OIDN's progress monitor: false (cancel) once the denoiser's stop flag or `render::STOP` is set.
unsafe extern "C" fn monitor(user: *mut c_void, _progress: f64) -> bool {
    // SAFETY: `user` is the `AtomicBool` of the denoiser's stop flag, alive while its filters are.
    let stop = unsafe { &*(user as *const AtomicBool) };
    !(stop.load(Ordering::Relaxed) || crate::render::STOP.load(Ordering::Relaxed))
}

type Monitor = unsafe extern "C" fn(*mut c_void, f64) -> bool;
/// The albedo and normal guides of a denoise, RGB triples row by row.
pub type Guides<'a> = (&'a [[f32; 3]], &'a [[f32; 3]]);
/// `OIDN_ERROR_CANCELLED` of oidn.h (after NONE, UNKNOWN, INVALID_ARGUMENT, INVALID_OPERATION,
/// OUT_OF_MEMORY, UNSUPPORTED_HARDWARE).
const OIDN_ERROR_CANCELLED: i32 = 6;

/// The committed filters and buffers of one image size (`Denoiser::prepare`).
struct Cache {
    width: usize,
    height: usize,
    guided: bool,
    buffers: Vec<Handle>,
    filters: Vec<Handle>,
}

impl Drop for Denoiser {
    fn drop(&mut self) {
        self.release_filters();
        // SAFETY: the device was created by `new` and is released once.
        unsafe { (self.api.release_device)(self.device) };
    }
}
