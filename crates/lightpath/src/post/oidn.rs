//! Intel Open Image Denoise's `RT` filter through its C API (the `oidn` crate's `sys`
//! module). The crate's `RayTracing` wrapper always sets a `color` image, so it cannot
//! prefilter an auxiliary image — an `RT` filter given only `albedo` (or only `normal`)
//! and an output, OIDN's documented final-frame setup, whose result the beauty's filter
//! then takes with `cleanAux` — and it copies every image into a buffer of its own. Here
//! images are shared with OIDN (no copies) and filtered in place.

use crate::error::OidnError;
use oidn::sys::*;
use std::ffi::{c_char, c_void, CStr};

/// OIDN's quality setting, as the C API numbers it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quality {
    High,
    Balanced,
    Fast,
}

impl Quality {
    fn raw(self) -> i32 {
        match self {
            Quality::High => OIDNQuality_OIDN_QUALITY_HIGH,
            Quality::Balanced => OIDNQuality_OIDN_QUALITY_BALANCED,
            Quality::Fast => OIDNQuality_OIDN_QUALITY_FAST,
        }
    }
}

/// One OIDN device (the CPU here; a GPU when the library has one).
pub struct Device(OIDNDevice);

impl Device {
    pub fn new() -> Result<Device, OidnError> {
        // SAFETY: plain calls of the C API; the handle is checked before use and
        // released once, in `drop`.
        let raw = unsafe { oidnNewDevice(OIDNDeviceType_OIDN_DEVICE_TYPE_DEFAULT) };
        if raw.is_null() {
            return Err(OidnError("cannot create a device".into()));
        }
        let device = Device(raw);
        unsafe { oidnCommitDevice(raw) };
        device.error()?;
        Ok(device)
    }

    /// The device's pending error, if any (reading it clears it).
    fn error(&self) -> Result<(), OidnError> {
        let mut message: *const c_char = std::ptr::null();
        // SAFETY: the device is live; OIDN writes a pointer to a NUL-terminated string
        // it owns, valid until the next call on the device, and copied here at once.
        let code = unsafe { oidnGetDeviceError(self.0, &mut message) };
        if code == OIDNError_OIDN_ERROR_NONE {
            return Ok(());
        }
        let text = if message.is_null() {
            format!("error {code}")
        } else {
            unsafe { CStr::from_ptr(message) }
                .to_string_lossy()
                .into_owned()
        };
        Err(OidnError(text))
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: created in `new`, released once; filters borrow the device, so none
        // outlives it.
        unsafe { oidnReleaseDevice(self.0) }
    }
}

/// The images a filter takes, fixed when it is made (changing which images are set
/// makes OIDN rebuild its network; changing only where they are does not).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Inputs {
    /// Prefilters an albedo image.
    Albedo,
    /// Prefilters a normal image.
    Normal,
    /// Filters HDR colour, with a (prefiltered, clean) albedo and normal if given.
    Color { albedo: bool, normal: bool },
}

/// An `RT` filter for images of one size, run in place.
pub struct Filter<'d> {
    device: &'d Device,
    raw: OIDNFilter,
    width: usize,
    height: usize,
    inputs: Inputs,
}

const fn name(s: &'static [u8]) -> *const c_char {
    s.as_ptr() as *const c_char
}

impl<'d> Filter<'d> {
    pub fn new(
        device: &'d Device,
        width: usize,
        height: usize,
        inputs: Inputs,
        quality: Quality,
    ) -> Result<Filter<'d>, OidnError> {
        // SAFETY: the device is live; a null filter is checked; names are
        // NUL-terminated literals.
        let raw = unsafe { oidnNewFilter(device.0, name(b"RT\0")) };
        if raw.is_null() {
            device.error()?;
            return Err(OidnError("cannot create an RT filter".into()));
        }
        let filter = Filter {
            device,
            raw,
            width,
            height,
            inputs,
        };
        unsafe {
            oidnSetFilterInt(raw, name(b"quality\0"), quality.raw());
            if let Inputs::Color { albedo, .. } = inputs {
                oidnSetFilterBool(raw, name(b"hdr\0"), true);
                // The auxiliary images given are prefiltered (or exact: a white albedo).
                oidnSetFilterBool(raw, name(b"cleanAux\0"), albedo);
            }
        }
        device.error()?;
        Ok(filter)
    }

    fn share(&self, image_name: &'static [u8], image: *mut f32) {
        // SAFETY: the filter is live; `image` points at width × height interleaved RGB
        // floats (checked by `run`) that stay borrowed until `run` returns.
        unsafe {
            oidnSetSharedFilterImage(
                self.raw,
                name(image_name),
                image as *mut c_void,
                OIDNFormat_OIDN_FORMAT_FLOAT3,
                self.width,
                self.height,
                0,
                0,
                0,
            )
        }
    }

    /// Filters `image` (interleaved RGB) in place, with `albedo` and `normal` as the
    /// filter's inputs ask.
    pub fn run(
        &mut self,
        image: &mut [f32],
        albedo: Option<&[f32]>,
        normal: Option<&[f32]>,
    ) -> Result<(), OidnError> {
        let n = self.width * self.height * 3;
        let fits = |v: Option<&[f32]>| v.is_none_or(|v| v.len() == n);
        if image.len() != n || !fits(albedo) || !fits(normal) {
            return Err(OidnError(format!(
                "an image is not {}×{} RGB",
                self.width, self.height
            )));
        }
        let main = image.as_mut_ptr();
        match self.inputs {
            Inputs::Albedo => self.share(b"albedo\0", main),
            Inputs::Normal => self.share(b"normal\0", main),
            Inputs::Color {
                albedo: with_albedo,
                normal: with_normal,
            } => {
                self.share(b"color\0", main);
                // OIDN only reads auxiliary images: the casts to *mut are its API's.
                match (with_albedo, albedo) {
                    (true, Some(a)) => self.share(b"albedo\0", a.as_ptr() as *mut f32),
                    (true, None) => return Err(OidnError("no albedo given".into())),
                    _ => {}
                }
                match (with_normal, normal) {
                    (true, Some(v)) => self.share(b"normal\0", v.as_ptr() as *mut f32),
                    (true, None) => return Err(OidnError("no normal given".into())),
                    _ => {}
                }
            }
        }
        // In place: OIDN supports output = input.
        self.share(b"output\0", main);
        // SAFETY: every image set above is live and of the right size for the duration
        // of the (synchronous) execution. The pointers stay set afterwards, unused until
        // the next `run` sets them again (unsetting them would make OIDN rebuild).
        unsafe {
            oidnCommitFilter(self.raw);
            oidnExecuteFilter(self.raw);
        }
        self.device.error()
    }
}

impl Drop for Filter<'_> {
    fn drop(&mut self) {
        // SAFETY: created in `new`, released once.
        unsafe { oidnReleaseFilter(self.raw) }
    }
}
