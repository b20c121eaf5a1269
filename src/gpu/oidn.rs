//! Intel Open Image Denoise (OIDN 2.x), loaded at run time with `libloading`: a render without
//! `--denoise` needs no library, and a missing one is a clear error naming what to install.
//! (Here, beside the Vulkan code, because it is the other foreign library we call: `unsafe`
//! lives only in src/gpu/.)
//!
//! The few C functions used are declared from OIDN 2.5's `include/OpenImageDenoise/oidn.h`:
//! device, buffers, the "RT" filter with `hdr` and `cleanAux`, errors and releases.
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
        let mut denoiser = Denoiser { api, device, device_type };
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

    /// Runs one "RT" filter (HDR, `clean_aux` as given) over `color` (RGB float triples) with the
    /// optional albedo and normal guides, in place of `color`'s pixels into `out`.
    fn filter(
        &mut self,
        images: &[(&CStr, &[[f32; 3]])],
        clean_aux: bool,
        hdr: bool,
        width: usize,
        height: usize,
    ) -> Result<Vec<[f32; 3]>, DenoiseError> {
        let bytes = width * height * 12;
        let mut buffers = Vec::new();
        let result = (|| {
            // SAFETY: a live device; every buffer holds width x height float triples, written
            // from slices of exactly that size, and is released below.
            unsafe {
                for (_, pixels) in images {
                    let b = (self.api.new_buffer)(self.device, bytes);
                    if b.is_null() {
                        self.check("allocating a buffer")?;
                    }
                    buffers.push(b);
                    (self.api.write_buffer)(b, 0, bytes, pixels.as_ptr().cast());
                }
                let output = (self.api.new_buffer)(self.device, bytes);
                buffers.push(output);
                self.check("allocating the buffers")?;
                let filter = (self.api.new_filter)(self.device, c"RT".as_ptr());
                self.check("creating the RT filter")?;
                let set = |name: &CStr, b: Handle| {
                    (self.api.set_filter_image)(filter, name.as_ptr(), b, OIDN_FORMAT_FLOAT3, width, height, 0, 0, 0)
                };
                for ((name, _), b) in images.iter().zip(&buffers) {
                    set(name, *b);
                }
                set(c"output", output);
                (self.api.set_filter_bool)(filter, c"hdr".as_ptr(), hdr);
                (self.api.set_filter_bool)(filter, c"cleanAux".as_ptr(), clean_aux);
                (self.api.commit_filter)(filter);
                let committed = self.check("setting up the RT filter");
                if committed.is_ok() {
                    (self.api.execute_filter)(filter);
                }
                (self.api.release_filter)(filter);
                committed?;
                self.check("running the RT filter")?;
                let mut out = vec![[0.0f32; 3]; width * height];
                (self.api.read_buffer)(output, 0, bytes, out.as_mut_ptr().cast());
                self.check("reading the result")?;
                Ok(out)
            }
        })();
        for b in buffers {
            // SAFETY: buffers created above, released once.
            unsafe { (self.api.release_buffer)(b) };
        }
        result
    }

    /// Denoises `color` (HDR radiance, row by row) with OIDN's "RT" filter, guided by `albedo`
    /// and `normal` where given; the guides are first denoised with RT filters of their own and
    /// then passed as clean (`cleanAux`), as OIDN's documentation recommends for noisy guides.
    pub fn denoise(
        &mut self,
        width: u32,
        height: u32,
        color: &[[f32; 3]],
        guides: Option<(&[[f32; 3]], &[[f32; 3]])>,
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
        let Some((albedo, normal)) = guides else {
            return self.filter(&[(c"color", color)], false, true, w, h);
        };
        sized("albedo", albedo)?;
        sized("normal", normal)?;
        // Prefilter the guides: albedo is LDR, the normal its own kind of image (OIDN 2.x takes
        // each as the "albedo" or "normal" input of an RT filter with no colour).
        let albedo = self.filter(&[(c"albedo", albedo)], false, false, w, h)?;
        let normal = self.filter(&[(c"normal", normal)], false, false, w, h)?;
        self.filter(&[(c"color", color), (c"albedo", &albedo), (c"normal", &normal)], true, true, w, h)
    }
}

impl Drop for Denoiser {
    fn drop(&mut self) {
        // SAFETY: the device was created by `new` and is released once.
        unsafe { (self.api.release_device)(self.device) };
    }
}
