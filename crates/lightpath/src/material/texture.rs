//! Image textures: PNG, JPEG and EXR images decoded once to linear RGBA, mip-mapped,
//! and looked up with bilinear filtering between the two mip levels the ray's footprint
//! falls between (trilinear).
//!
//! ```toml
//! [materials.wood]
//! type = "diffuse"
//! albedo = [1, 1, 1]                       # multiplies the texture
//! albedo_texture = "textures/wood.png"     # sRGB-decoded colour
//! roughness_texture = "textures/rough.png" # linear data (its green channel, as glTF)
//! normal_texture = "textures/normal.png"   # tangent space, linear
//! texture_wrap = "repeat"                  # repeat | clamp | mirror
//! ```
//!
//! UVs follow glTF: (0, 0) is the image's top-left corner, `v` grows downwards.
//! Colour images (base colour, emission) are decoded from sRGB; data images (roughness,
//! metallic, normals, transmission) are read as linear values. EXR images are linear.
//!
//! Bilinear and mip filtering average decoded (linear) values, so a texture's mean
//! reflectance is the same at every distance and texel frequency. Cycles differs: it keeps
//! 8-bit sRGB images as bytes, interpolates the encoded values and decodes afterwards
//! (`kernel/svm/image.h`, `NODE_IMAGE_COMPRESS_AS_SRGB`), which darkens every transition
//! between texels: a checker of 8-texel cells is 4–7 % darker in Cycles, one of 1-texel
//! cells up to 39 % (benches/materials/RESULTS.md, "Checker crates: Cycles filters sRGB bytes").

use glam::{Vec2, Vec4};
use std::path::Path;

/// What happens outside [0, 1] in one texture direction (glTF's sampler wrap modes).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Wrap {
    #[default]
    Repeat,
    Clamp,
    Mirror,
}

impl Wrap {
    /// The texel index for integer coordinate `i` of a row or column of `n` texels.
    #[inline]
    fn index(self, i: i32, n: i32) -> usize {
        let k = match self {
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::Clamp => i.clamp(0, n - 1),
            Wrap::Mirror => {
                let m = i.rem_euclid(2 * n);
                if m < n {
                    m
                } else {
                    2 * n - 1 - m
                }
            }
        };
        k as usize
    }
}

/// How an image's 8- or 16-bit values become linear values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorSpace {
    /// Colour: the sRGB transfer function is undone (alpha stays linear).
    Srgb,
    /// Data (roughness, metallic, normals): values as stored.
    Linear,
}

/// The sRGB electro-optical transfer function (IEC 61966-2-1).
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

struct Level {
    width: u32,
    height: u32,
    texels: Vec<Vec4>,
}

/// A linear RGBA image and its mip levels, each half the size of the one before (a 2×2
/// box filter, the last row or column repeated for odd sizes) down to 1×1.
pub struct MipMap {
    levels: Vec<Level>,
}

impl std::fmt::Debug for MipMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "MipMap({}x{}, {} levels)",
            self.width(),
            self.height(),
            self.levels.len()
        )
    }
}

impl MipMap {
    /// # Panics
    /// If `texels` does not hold `width × height` values or a size is zero.
    pub fn new(width: u32, height: u32, texels: Vec<Vec4>) -> MipMap {
        assert!(width > 0 && height > 0 && texels.len() == (width * height) as usize);
        let mut levels = vec![Level {
            width,
            height,
            texels,
        }];
        loop {
            let prev = levels.last().expect("level 0 exists");
            if prev.width == 1 && prev.height == 1 {
                break;
            }
            let (w, h) = ((prev.width / 2).max(1), (prev.height / 2).max(1));
            let at = |x: u32, y: u32| {
                prev.texels[(y.min(prev.height - 1) * prev.width + x.min(prev.width - 1)) as usize]
            };
            let mut texels = Vec::with_capacity((w * h) as usize);
            for y in 0..h {
                for x in 0..w {
                    let (x0, y0) = (2 * x, 2 * y);
                    texels.push(
                        0.25 * (at(x0, y0) + at(x0 + 1, y0) + at(x0, y0 + 1) + at(x0 + 1, y0 + 1)),
                    );
                }
            }
            levels.push(Level {
                width: w,
                height: h,
                texels,
            });
        }
        MipMap { levels }
    }

    pub fn width(&self) -> u32 {
        self.levels[0].width
    }

    pub fn height(&self) -> u32 {
        self.levels[0].height
    }

    pub fn levels(&self) -> usize {
        self.levels.len()
    }

    /// Bytes held by all levels.
    pub fn bytes(&self) -> usize {
        self.levels.iter().map(|l| l.texels.len() * 16).sum()
    }

    /// Bilinear lookup in one level; texel centres sit at half-integer coordinates.
    pub fn bilinear(&self, level: usize, uv: Vec2, wrap: [Wrap; 2]) -> Vec4 {
        let l = &self.levels[level.min(self.levels.len() - 1)];
        let (w, h) = (l.width as i32, l.height as i32);
        let x = uv.x * w as f32 - 0.5;
        let y = uv.y * h as f32 - 0.5;
        if !(x.is_finite() && y.is_finite()) {
            return Vec4::ZERO;
        }
        // Far outside the image, wrap before converting to integers.
        let (x, y) = (x.clamp(-1e6, 1e6), y.clamp(-1e6, 1e6));
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i32, y0 as i32);
        // The two columns and two rows wrapped once each, not once a texel.
        let (i0, i1) = (wrap[0].index(x0, w), wrap[0].index(x0 + 1, w));
        let (r0, r1) = (
            wrap[1].index(y0, h) * l.width as usize,
            wrap[1].index(y0 + 1, h) * l.width as usize,
        );
        let px = |row: usize, i: usize| l.texels[row + i];
        let top = px(r0, i0) * (1.0 - fx) + px(r0, i1) * fx;
        let bottom = px(r1, i0) * (1.0 - fx) + px(r1, i1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// Trilinear lookup: `lod` 0 is the full image, each unit one level smaller.
    pub fn lookup(&self, uv: Vec2, lod: f32, wrap: [Wrap; 2]) -> Vec4 {
        let top = (self.levels.len() - 1) as f32;
        let lod = if lod.is_finite() {
            lod.clamp(0.0, top)
        } else {
            0.0
        };
        let l0 = lod.floor();
        let t = lod - l0;
        let a = self.bilinear(l0 as usize, uv, wrap);
        if t == 0.0 {
            return a;
        }
        a * (1.0 - t) + self.bilinear(l0 as usize + 1, uv, wrap) * t
    }

    /// Decodes a PNG, JPEG or EXR image (told apart by their first bytes) to linear
    /// RGBA; 8- and 16-bit images by `space`, EXR as stored. The size its header declares
    /// is checked against the limits (`limits.rs`) before any pixel is allocated.
    pub fn decode(bytes: &[u8], space: ColorSpace) -> Result<MipMap, String> {
        if bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
            let (w, h, texels) = crate::output::decode_exr_rgba(bytes)?;
            if w == 0 || h == 0 {
                return Err("the image is empty".into());
            }
            let texels = texels.into_iter().map(Vec4::from_array).collect();
            return Ok(MipMap::new(w as u32, h as u32, texels));
        }
        let img = decode_8_or_16_bit(bytes)?;
        let (w, h) = (img.width(), img.height());
        if w == 0 || h == 0 {
            return Err("the image is empty".into());
        }
        let texels: Vec<Vec4> = match (&img, space) {
            (
                image::DynamicImage::ImageRgb8(_)
                | image::DynamicImage::ImageRgba8(_)
                | image::DynamicImage::ImageLuma8(_)
                | image::DynamicImage::ImageLumaA8(_),
                _,
            ) => {
                let lut: Vec<f32> = (0..256)
                    .map(|i| {
                        let c = i as f32 / 255.0;
                        match space {
                            ColorSpace::Srgb => srgb_to_linear(c),
                            ColorSpace::Linear => c,
                        }
                    })
                    .collect();
                img.to_rgba8()
                    .pixels()
                    .map(|p| {
                        let [r, g, b, a] = p.0;
                        Vec4::new(
                            lut[r as usize],
                            lut[g as usize],
                            lut[b as usize],
                            a as f32 / 255.0,
                        )
                    })
                    .collect()
            }
            _ => img
                .to_rgba32f()
                .pixels()
                .map(|p| {
                    let [r, g, b, a] = p.0;
                    let f = |c: f32| match space {
                        ColorSpace::Srgb => srgb_to_linear(c),
                        ColorSpace::Linear => c,
                    };
                    Vec4::new(f(r), f(g), f(b), a)
                })
                .collect(),
        };
        Ok(MipMap::new(w, h, texels))
    }

    /// Reads and decodes an image file, through `limits::read_input` like every input of
    /// a render (within the input-size limit, and noted in the render's identity).
    pub fn read(path: &Path, space: ColorSpace) -> Result<MipMap, String> {
        let bytes = crate::limits::read_input(path).map_err(|e| format!("cannot read it: {e}"))?;
        MipMap::decode(&bytes, space)
    }
}

/// Bytes per texel a decoded 8- or 16-bit image costs at most: the decoder's image (up to
/// 8), its RGBA conversion (up to 16), and the mip-mapped texels (16, a third more for the
/// smaller levels).
const DECODE_BYTES_PER_TEXEL: u64 = 8 + 16 + 22;

/// A PNG or JPEG, after checking the size its header declares against the pixel and
/// memory limits; the decoder is held to the memory limit too.
fn decode_8_or_16_bit(bytes: &[u8]) -> Result<image::DynamicImage, String> {
    let limits = crate::limits::Limits::current();
    let reader = || {
        image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| e.to_string())
    };
    let (w, h) = reader()?.into_dimensions().map_err(|e| e.to_string())?;
    let texels = w as u64 * h as u64;
    let what = format!("a {w}x{h} texture");
    limits.check_pixels(texels, &what)?;
    limits.check_memory(texels.saturating_mul(DECODE_BYTES_PER_TEXEL), &what)?;
    let mut reader = reader()?;
    let mut decoder_limits = image::Limits::default();
    decoder_limits.max_alloc = Some(limits.memory);
    reader.limits(decoder_limits);
    reader.decode().map_err(|e| e.to_string())
}

/// A placement of texture coordinates (KHR_texture_transform): `uv' = M·(u, v, 1)`,
/// M = translation · rotation · scale, stored as the rows of a 2×3 matrix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    pub rows: [[f32; 3]; 2],
}

impl Default for UvTransform {
    fn default() -> Self {
        UvTransform {
            rows: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        }
    }
}

impl UvTransform {
    /// KHR_texture_transform's `offset`, `rotation` (radians) and `scale`.
    pub fn new(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> UvTransform {
        let (s, c) = rotation.sin_cos();
        // The extension's GLSL matrix T · R · S, whose rotation has columns (cos, sin)
        // and (−sin, cos).
        UvTransform {
            rows: [
                [c * scale[0], -s * scale[1], offset[0]],
                [s * scale[0], c * scale[1], offset[1]],
            ],
        }
    }

    pub fn apply(&self, uv: Vec2) -> Vec2 {
        let [a, b] = self.rows;
        Vec2::new(
            a[0] * uv.x + a[1] * uv.y + a[2],
            b[0] * uv.x + b[1] * uv.y + b[2],
        )
    }

    /// How much the transform stretches lengths (the root of its determinant), for the
    /// footprint.
    fn scale(&self) -> f32 {
        let [a, b] = self.rows;
        (a[0] * b[1] - a[1] * b[0]).abs().sqrt()
    }
}

/// A texture as a material uses it: an image shared between materials, its wrap modes
/// and UV placement.
#[derive(Clone, Debug)]
pub struct Texture {
    pub image: std::sync::Arc<MipMap>,
    pub wrap: [Wrap; 2],
    pub transform: UvTransform,
}

impl Texture {
    /// The filtered value at `uv` for a footprint `width` wide in UV units.
    pub fn eval(&self, uv: Vec2, width: f32) -> Vec4 {
        let st = self.transform.apply(uv);
        let size = (self.image.width() as f32 * self.image.height() as f32).sqrt();
        let texels = width * self.transform.scale() * size;
        let lod = if texels > 1.0 { texels.log2() } else { 0.0 };
        self.image.lookup(st, lod, self.wrap)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker2() -> MipMap {
        // Row 0: red, green; row 1: blue, white.
        MipMap::new(
            2,
            2,
            vec![
                Vec4::new(1.0, 0.0, 0.0, 1.0),
                Vec4::new(0.0, 1.0, 0.0, 1.0),
                Vec4::new(0.0, 0.0, 1.0, 1.0),
                Vec4::new(1.0, 1.0, 1.0, 1.0),
            ],
        )
    }

    #[test]
    fn texel_centres_return_texels_and_midpoints_average() {
        let m = checker2();
        let w = [Wrap::Clamp; 2];
        assert_eq!(
            m.bilinear(0, Vec2::new(0.25, 0.25), w),
            Vec4::new(1.0, 0.0, 0.0, 1.0)
        );
        assert_eq!(m.bilinear(0, Vec2::new(0.75, 0.75), w), Vec4::ONE);
        let mid = m.bilinear(0, Vec2::new(0.5, 0.25), w);
        assert!((mid - Vec4::new(0.5, 0.5, 0.0, 1.0)).abs().max_element() < 1e-6);
        // The image centre averages all four.
        let c = m.bilinear(0, Vec2::new(0.5, 0.5), w);
        assert!((c - Vec4::new(0.5, 0.5, 0.5, 1.0)).abs().max_element() < 1e-6);
    }

    #[test]
    fn wrap_modes() {
        let m = checker2();
        let red = Vec4::new(1.0, 0.0, 0.0, 1.0);
        let green = Vec4::new(0.0, 1.0, 0.0, 1.0);
        // One image to the right: repeat finds red again, mirror finds green (the image
        // flipped), clamp the right column (green).
        let uv = Vec2::new(1.25, 0.25);
        assert_eq!(m.bilinear(0, uv, [Wrap::Repeat; 2]), red);
        assert_eq!(m.bilinear(0, uv, [Wrap::Mirror; 2]), green);
        assert_eq!(m.bilinear(0, uv, [Wrap::Clamp; 2]), green);
        assert_eq!(
            m.bilinear(0, Vec2::new(-0.75, 0.25), [Wrap::Repeat; 2]),
            red
        );
        assert_eq!(
            m.bilinear(0, Vec2::new(-0.25, 0.25), [Wrap::Mirror; 2]),
            red
        );
    }

    #[test]
    fn mip_levels_average_and_lod_blends() {
        let m = checker2();
        assert_eq!(m.levels(), 2);
        let avg = Vec4::new(0.5, 0.5, 0.5, 1.0);
        let w = [Wrap::Repeat; 2];
        assert!(
            (m.lookup(Vec2::new(0.25, 0.25), 1.0, w) - avg)
                .abs()
                .max_element()
                < 1e-6
        );
        let half = m.lookup(Vec2::new(0.25, 0.25), 0.5, w);
        let want = 0.5 * (Vec4::new(1.0, 0.0, 0.0, 1.0) + avg);
        assert!((half - want).abs().max_element() < 1e-6);
        // A footprint of one texel or less reads level 0; the whole image, the last.
        let t = Texture {
            image: std::sync::Arc::new(checker2()),
            wrap: w,
            transform: UvTransform::default(),
        };
        assert_eq!(
            t.eval(Vec2::new(0.25, 0.25), 0.1),
            Vec4::new(1.0, 0.0, 0.0, 1.0)
        );
        assert!(
            (t.eval(Vec2::new(0.25, 0.25), 1.0) - avg)
                .abs()
                .max_element()
                < 1e-6
        );
    }

    #[test]
    fn odd_sizes_reduce_to_one_texel() {
        let m = MipMap::new(5, 3, vec![Vec4::splat(0.5); 15]);
        assert_eq!(m.levels(), 3);
        assert_eq!(
            m.lookup(Vec2::new(0.3, 0.7), 10.0, [Wrap::Clamp; 2]),
            Vec4::splat(0.5)
        );
    }

    #[test]
    fn srgb_decoding_of_png_values() {
        // A 1×1 PNG of (128, 255, 0, 255): colour is decoded from sRGB, data is not.
        let mut png = Vec::new();
        image::RgbaImage::from_pixel(1, 1, image::Rgba([128, 255, 0, 255]))
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        let c = MipMap::decode(&png, ColorSpace::Srgb).unwrap();
        let d = MipMap::decode(&png, ColorSpace::Linear).unwrap();
        let w = [Wrap::Clamp; 2];
        let (c, d) = (
            c.bilinear(0, Vec2::splat(0.5), w),
            d.bilinear(0, Vec2::splat(0.5), w),
        );
        assert!((c.x - 0.2158605).abs() < 1e-5, "{c}");
        assert!((d.x - 128.0 / 255.0).abs() < 1e-6);
        assert_eq!((c.y, c.z, c.w), (1.0, 0.0, 1.0));
        assert!(MipMap::decode(b"not an image", ColorSpace::Srgb).is_err());
    }

    #[test]
    fn filtering_averages_decoded_values_not_srgb_bytes() {
        // A 2×2 checker of sRGB bytes 26 and 204 (the crate's dim and bright channels):
        // the midpoint between texels and the 1×1 mip level are the mean of the decoded
        // values, 0.307, not the decoded mean byte, srgb(115) = 0.171 (Cycles' bilinear).
        let (dim, bright) = (26u8, 204u8);
        let mut png = Vec::new();
        image::RgbaImage::from_fn(2, 2, |x, y| {
            let c = if (x + y) % 2 == 0 { dim } else { bright };
            image::Rgba([c, c, c, 255])
        })
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
        let m = MipMap::decode(&png, ColorSpace::Srgb).unwrap();
        let mean =
            0.5 * (srgb_to_linear(dim as f32 / 255.0) + srgb_to_linear(bright as f32 / 255.0));
        assert!((mean - 0.3071).abs() < 1e-3, "{mean}");
        let w = [Wrap::Clamp; 2];
        let midpoint = m.bilinear(0, Vec2::new(0.5, 0.25), w);
        let top = m.lookup(Vec2::splat(0.5), 1.0, w);
        for v in [midpoint, top] {
            assert!((v.x - mean).abs() < 1e-6, "{v} against {mean}");
        }
    }

    #[test]
    fn a_texture_declaring_more_pixels_than_the_limit_is_refused_before_decoding() {
        // A PNG signature, a header (IHDR) of 65535 × 65535 RGBA8 texels and no
        // pixel data: 17 GB, were it allocated.
        let mut png = b"\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR".to_vec();
        png.extend(65535u32.to_be_bytes());
        png.extend(65535u32.to_be_bytes());
        png.extend([8, 6, 0, 0, 0]);
        let crc = png_crc(&png[12..]);
        png.extend(crc.to_be_bytes());
        // An empty IDAT chunk: the header is read up to the first one.
        png.extend(b"\0\0\0\0IDAT");
        png.extend(png_crc(b"IDAT").to_be_bytes());
        let e = MipMap::decode(&png, ColorSpace::Srgb).unwrap_err();
        assert!(
            e.contains("65535x65535 texture") && e.contains("LIGHTPATH_MAX_"),
            "{e}"
        );
    }

    /// The CRC-32 PNG chunks end with (ISO 3309).
    fn png_crc(bytes: &[u8]) -> u32 {
        let mut c = !0u32;
        for &b in bytes {
            c ^= b as u32;
            for _ in 0..8 {
                c = if c & 1 == 1 {
                    0xedb8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
            }
        }
        !c
    }

    #[test]
    fn jpeg_and_exr_textures_decode() {
        let w = [Wrap::Clamp; 2];
        // A flat 8×8 JPEG of sRGB 128: lossy, but a flat block decodes within a level.
        let mut jpeg = Vec::new();
        image::RgbImage::from_pixel(8, 8, image::Rgb([128, 128, 128]))
            .write_to(
                &mut std::io::Cursor::new(&mut jpeg),
                image::ImageFormat::Jpeg,
            )
            .unwrap();
        let c = MipMap::decode(&jpeg, ColorSpace::Srgb)
            .unwrap()
            .bilinear(0, Vec2::splat(0.5), w);
        let (lo, hi) = (srgb_to_linear(127.0 / 255.0), srgb_to_linear(129.0 / 255.0));
        assert!((lo..=hi).contains(&c.x) && (lo..=hi).contains(&c.z), "{c}");
        // An EXR keeps its linear values, above 1 too, whatever the colour space.
        let path = std::env::temp_dir().join(format!("lightpath-tex-{}.exr", std::process::id()));
        exr::prelude::write_rgba_file(&path, 2, 1, |x, _| {
            if x == 0 {
                (4.0f32, 0.5f32, 0.25f32, 1.0f32)
            } else {
                (0.0, 0.0, 1.0, 1.0)
            }
        })
        .unwrap();
        let bytes = std::fs::read(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        let m = MipMap::decode(&bytes, ColorSpace::Srgb).unwrap();
        assert_eq!(
            m.bilinear(0, Vec2::new(0.25, 0.5), w),
            Vec4::new(4.0, 0.5, 0.25, 1.0)
        );
        assert_eq!(
            m.bilinear(0, Vec2::new(0.75, 0.5), w),
            Vec4::new(0.0, 0.0, 1.0, 1.0)
        );
    }

    #[test]
    fn texture_transform_matches_the_extension() {
        // The extension's example: offset (0.5, 0), rotation π/2, scale (2, 2).
        let t = UvTransform::new([0.5, 0.0], std::f32::consts::FRAC_PI_2, [2.0, 2.0]);
        let p = t.apply(Vec2::new(1.0, 0.0));
        // R·(2, 0) = (2cos, 2sin) = (0, 2), then + offset.
        assert!((p - Vec2::new(0.5, 2.0)).length() < 1e-5, "{p}");
        assert!((t.scale() - 2.0).abs() < 1e-5);
    }
}
