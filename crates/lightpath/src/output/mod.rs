//! Writing renders: one single-part EXR with every AOV (beauty as R, G, B, A and each AOV
//! as `<name>.R/.G/.B`, the expressions in the header) and a PNG preview of the beauty.
//! Both are written beside the target, synced, then renamed into place together
//! (`atomic`), so a crash never leaves a half-written image, or a mismatched pair, under
//! the real names. A USD stage's several render products are several such files cut
//! from the one film (`products`).

pub mod atomic;
mod exr;
pub mod naming;
mod png;
pub mod products;
mod read;
pub mod target;

pub use self::exr::{
    aov_attributes, derived_aovs, shadow_matte, software, stage_film, stage_image, write_channels,
    write_exr, write_film, write_image, DerivedAov, ExrCompression, ExrHeader, ExrOptions,
};
pub use self::png::{stage_png, stage_png_rgb, write_png, write_png_rgb};
pub use self::read::{
    check_exr_file, decode_exr_rgba, read_exr, read_exr_header, ExrContents, ExrLayout,
};
pub use crate::aov::naming::{channel_names, AOV_ATTRIBUTE_PREFIX};
