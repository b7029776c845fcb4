//! Reading line-based text formats (OBJ, MTL): the file as bytes with a check that it is
//! text, lines with their numbers, words with their columns, and numbers whose errors say
//! where they are and what was expected.

use crate::scene::desc::{Origin, TextureRef};
use crate::scene::SceneError;
use std::borrow::Cow;
use std::path::Path;

/// The bytes of `path`, a `what` file named at `at`; the error names the file and the
/// OS reason. Only regular files are read (a device such as /dev/zero never ends).
pub fn read(path: &Path, at: &Origin, what: &str) -> Result<Vec<u8>, SceneError> {
    let cannot = |reason: crate::error::ReadError| {
        at.error(format!(
            "cannot read {what} file {}: {reason}",
            path.display()
        ))
    };
    // Regular files only, within `Limits::file_bytes` (`/dev/zero` named as an OBJ).
    crate::limits::read_input(path).map_err(cannot)
}

/// Refuses a file that is not text, naming what it looks like instead.
pub fn not_binary(bytes: &[u8], file: &str, what: &str) -> Result<(), SceneError> {
    let at = Origin::file(file);
    let start = bytes.trim_ascii_start();
    let looks = if bytes.starts_with(b"glTF") {
        Some("a binary glTF (.glb) file")
    } else if start.starts_with(b"{") {
        Some("a JSON file (glTF?)")
    } else if bytes.starts_with(b"ply") {
        Some("a PLY file")
    } else if bytes.starts_with(b"\x89PNG") || bytes.starts_with(b"\xff\xd8\xff") {
        Some("an image")
    } else {
        None
    };
    if let Some(kind) = looks {
        return Err(at.error(format!("this is {kind}, not an {what} file")));
    }
    let head = &bytes[..bytes.len().min(1 << 16)];
    if let Some(i) = head.iter().position(|&b| b == 0) {
        let line = head[..i].iter().filter(|&&b| b == b'\n').count() + 1;
        return Err(Origin {
            file: file.into(),
            line,
            col: 0,
        }
        .error(format!("binary data (a NUL byte), not an {what} text file")));
    }
    Ok(())
}

/// One logical line (continuation lines joined), without its comment.
pub struct Line<'a> {
    text: Cow<'a, str>,
    file: &'a str,
    number: usize,
}

/// A whitespace-separated word and its 1-based column.
#[derive(Clone, Copy)]
pub struct Word<'a> {
    pub text: &'a str,
    pub col: usize,
}

/// The lines of a file: `#` starts a comment, a trailing `\` continues the line.
pub fn lines<'a>(bytes: &'a [u8], file: &'a str) -> impl Iterator<Item = Line<'a>> {
    let mut rest = bytes;
    let mut number = 0;
    std::iter::from_fn(move || {
        if rest.is_empty() {
            return None;
        }
        number += 1;
        let first = number;
        let take = |rest: &mut &'a [u8]| {
            let end = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
            let line = &rest[..end];
            *rest = &rest[(end + 1).min(rest.len())..];
            let line = line.strip_suffix(b"\r").unwrap_or(line);
            let line = match line.iter().position(|&b| b == b'#') {
                Some(i) => &line[..i],
                None => line,
            };
            String::from_utf8_lossy(line)
        };
        let mut text = take(&mut rest);
        while text.trim_end().ends_with('\\') && !rest.is_empty() {
            number += 1;
            let mut joined = text.trim_end().trim_end_matches('\\').to_string();
            joined.push(' ');
            joined.push_str(&take(&mut rest));
            text = Cow::Owned(joined);
        }
        Some(Line {
            text,
            file,
            number: first,
        })
    })
}

impl<'a> Line<'a> {
    pub fn words(&self) -> impl Iterator<Item = Word<'_>> {
        let base = self.text.as_ptr() as usize;
        self.text.split_ascii_whitespace().map(move |w| Word {
            text: w,
            col: w.as_ptr() as usize - base + 1,
        })
    }

    pub fn origin(&self, word: Word) -> Origin {
        Origin {
            file: self.file.to_string(),
            line: self.number,
            col: word.col,
        }
    }

    /// The end of the line, for "found end of line".
    fn end(&self) -> Origin {
        Origin {
            file: self.file.to_string(),
            line: self.number,
            col: self.text.trim_end().len() + 1,
        }
    }

    /// The rest of the line after `keyword`, trimmed (names may contain spaces).
    pub fn rest_after(&self, keyword: Word) -> &str {
        let start = keyword.col - 1 + keyword.text.len();
        self.text[start..].trim()
    }

    /// A finite number for `what` (after `keyword`).
    pub fn number(&self, word: Option<Word>, keyword: Word, what: &str) -> Result<f32, SceneError> {
        let Some(w) = word else {
            return Err(self.end().error(format!(
                "'{}': expected a number for {what}, found the end of the line",
                keyword.text
            )));
        };
        let x: f32 = w.text.parse().map_err(|_| {
            self.origin(w)
                .error(format!("expected a number for {what}, found '{}'", w.text))
        })?;
        if !x.is_finite() {
            return Err(self
                .origin(w)
                .error(format!("{what} '{}' is not a finite number", w.text)));
        }
        Ok(x)
    }

    /// Three finite numbers (further ones, such as a `w` or vertex colours, are ignored).
    pub fn vec3<'w>(
        &self,
        mut words: impl Iterator<Item = Word<'w>>,
        keyword: Word,
        what: &str,
    ) -> Result<[f32; 3], SceneError> {
        let mut v = [0.0; 3];
        for (c, axis) in v.iter_mut().zip(["x", "y", "z"]) {
            *c = self.number(words.next(), keyword, &format!("the {what}'s {axis}"))?;
        }
        Ok(v)
    }

    /// An MTL colour: `r g b`, or one number for grey.
    pub fn colour<'w>(
        &self,
        mut words: impl Iterator<Item = Word<'w>>,
        keyword: Word,
    ) -> Result<[f32; 3], SceneError> {
        let what = keyword.text;
        let first = words.next();
        if let Some(w) = first.filter(|w| w.text == "spectral" || w.text == "xyz") {
            return Err(self.origin(w).error(format!(
                "'{what} {}' is not supported: expected {what} r g b",
                w.text
            )));
        }
        let r = self.number(first, keyword, what)?;
        match words.next() {
            None => Ok([r; 3]),
            g => {
                let g = self.number(g, keyword, what)?;
                let b = self.number(words.next(), keyword, what)?;
                Ok([r, g, b])
            }
        }
    }

    /// A texture statement: options (`-bm 1`, `-s 1 1 1`, …) then the file name, relative
    /// to `dir`.
    pub fn texture(&self, keyword: Word, dir: &Path) -> Result<TextureRef, SceneError> {
        let words: Vec<Word> = self.words().skip(1).collect();
        let mut i = 0;
        let mut bump_scale = 1.0;
        while i < words.len() && words[i].text.starts_with('-') {
            let option = words[i].text;
            i += 1;
            let arity = match option {
                "-o" | "-s" | "-t" => 3,
                "-mm" => 2,
                "-blendu" | "-blendv" | "-cc" | "-clamp" | "-texres" | "-bm" | "-boost"
                | "-imfchan" | "-type" => 1,
                _ => {
                    return Err(self.origin(words[i - 1]).error(format!(
                        "unknown texture option '{option}' of '{}'",
                        keyword.text
                    )))
                }
            };
            // -o/-s/-t take one to three numbers.
            let mut taken = 0;
            while taken < arity && i < words.len() {
                let numeric = words[i].text.parse::<f32>().is_ok();
                if arity == 3 && taken > 0 && !numeric {
                    break;
                }
                if option == "-bm" {
                    bump_scale = self.number(Some(words[i]), keyword, "-bm")?;
                }
                i += 1;
                taken += 1;
            }
        }
        let Some(first) = words.get(i) else {
            return Err(self.end().error(format!(
                "'{}': expected a file name, found the end of the line",
                keyword.text
            )));
        };
        let name = self.text[first.col - 1..].trim();
        Ok(TextureRef {
            path: dir.join(name),
            scale: bump_scale,
            origin: self.origin(*first),
        })
    }
}
