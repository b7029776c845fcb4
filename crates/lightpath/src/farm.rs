//! Splitting a frame over a farm: the parts (`--first-sample/--spp` ranges or `--crop`
//! row strips) and the scripts that run them on Slurm (`sbatch` job array + a merge job
//! that depends on it) or on one workstation with GNU `parallel`.
//!
//! Every part renders with the frame's own sample numbers, so `lightpath merge` of the
//! parts equals the single-process render: exactly for tiles, to float rounding for
//! sample ranges (the merge averages per-range means).

use crate::film::PixelWindow;
use std::path::{Path, PathBuf};

/// How a frame is split.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SplitBy {
    /// Sample ranges of the whole frame.
    Samples,
    /// Horizontal strips of rows, all samples each.
    Tiles,
}

impl SplitBy {
    pub fn parse(s: &str) -> Result<SplitBy, crate::error::InvalidValue> {
        match s {
            "samples" => Ok(SplitBy::Samples),
            "tiles" => Ok(SplitBy::Tiles),
            other => Err(crate::error::InvalidValue(format!(
                "expected samples or tiles, got '{other}'"
            ))),
        }
    }
}

/// One task's extra render arguments.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Part {
    Samples { first: u64, spp: u32 },
    Tile(PixelWindow),
}

impl Part {
    /// The `lightpath render` arguments selecting this part.
    pub fn args(&self) -> Vec<String> {
        match self {
            Part::Samples { first, spp } => vec![
                "--first-sample".into(),
                first.to_string(),
                "--spp".into(),
                spp.to_string(),
            ],
            Part::Tile(w) => vec!["--crop".into(), w.to_string()],
        }
    }
}

/// Splits a frame of `spp` samples and `resolution` into `tasks` parts: sample ranges as
/// even as integers allow, or strips of rows likewise.
pub fn split(by: SplitBy, tasks: u32, spp: u32, resolution: [u32; 2]) -> Result<Vec<Part>, String> {
    if tasks == 0 {
        return Err("--tasks must be at least 1".into());
    }
    let even = |total: u32| -> Vec<(u32, u32)> {
        let (base, extra) = (total / tasks, total % tasks);
        let mut at = 0;
        (0..tasks)
            .map(|i| {
                let n = base + (i < extra) as u32;
                at += n;
                (at - n, at)
            })
            .collect()
    };
    match by {
        SplitBy::Samples => {
            if spp < tasks {
                return Err(format!(
                    "{spp} samples per pixel cannot be split into {tasks} sample ranges: use fewer tasks or --by tiles"
                ));
            }
            Ok(even(spp)
                .into_iter()
                .map(|(a, b)| Part::Samples {
                    first: a as u64,
                    spp: b - a,
                })
                .collect())
        }
        SplitBy::Tiles => {
            let [w, h] = resolution;
            if h < tasks {
                return Err(format!(
                    "{h} rows cannot be split into {tasks} tiles: use fewer tasks or --by samples"
                ));
            }
            Ok(even(h)
                .into_iter()
                .map(|(a, b)| {
                    Part::Tile(PixelWindow {
                        x0: 0,
                        y0: a,
                        x1: w,
                        y1: b,
                    })
                })
                .collect())
        }
    }
}

/// A farm job: the binary, the scene, the render arguments every part shares, the parts
/// and the merged output.
#[derive(Clone, Debug)]
pub struct FarmJob {
    pub lightpath: PathBuf,
    pub scene: String,
    pub render_args: Vec<String>,
    pub parts: Vec<Part>,
    pub output: PathBuf,
    /// Extra `sbatch` options for both jobs (partition, time limit, …).
    pub sbatch_args: Vec<String>,
    /// `lightpath denoise` options when the merged frame is to be denoised (the render
    /// options' `--denoise`, `--keep-noisy`, `--denoise-quality`): the parts are rendered
    /// noisy, merged into `<parts>/merged.exr`, and that is denoised into the output.
    pub denoise: Option<Vec<String>>,
    /// A USD stage's render products' file names when there are several and `output` is
    /// a directory: each part renders them into a directory of its own
    /// (`<parts>/part-NNNN/`), and each product is merged (and denoised) on its own into
    /// `output/<name>`. Empty: one file per part and one merged file, `output`.
    pub products: Vec<PathBuf>,
}

/// Quotes a word for POSIX shells.
pub fn shell_quote(s: &str) -> String {
    if !s.is_empty()
        && s.bytes()
            .all(|b| b.is_ascii_alphanumeric() || b"-_./=,:+@%".contains(&b))
    {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

fn quote_all(words: &[String]) -> String {
    words
        .iter()
        .map(|w| shell_quote(w))
        .collect::<Vec<_>>()
        .join(" ")
}

impl FarmJob {
    /// Where the parts and logs go: `<output without .exr>.parts/`.
    pub fn parts_dir(&self) -> PathBuf {
        let mut name = self
            .output
            .file_stem()
            .map(|s| s.to_os_string())
            .unwrap_or_else(|| "render".into());
        name.push(".parts");
        self.output.with_file_name(name)
    }

    /// Part `i`'s output: its EXR, or with several products the directory (named with a
    /// trailing `/`, so the render reads it as one) they go into.
    fn part_path(&self, i: usize) -> PathBuf {
        match self.products.is_empty() {
            true => self.parts_dir().join(format!("part-{i:04}.exr")),
            false => self.parts_dir().join(format!("part-{i:04}/")),
        }
    }

    /// The files merged into one output: `(part files, merged file, final file)` per
    /// product (one entry without products). The merged file is the final one unless it
    /// is to be denoised.
    fn merges(&self) -> Vec<(Vec<PathBuf>, PathBuf, PathBuf)> {
        let merged = |name: &Path| match self.denoise {
            Some(_) => self.parts_dir().join("merged").join(name),
            None => self.output.join(name),
        };
        if self.products.is_empty() {
            let parts = (0..self.parts.len()).map(|i| self.part_path(i)).collect();
            let merged = match self.denoise {
                Some(_) => self.parts_dir().join("merged.exr"),
                None => self.output.clone(),
            };
            return vec![(parts, merged, self.output.clone())];
        }
        self.products
            .iter()
            .map(|name| {
                let parts = (0..self.parts.len())
                    .map(|i| self.part_path(i).join(name))
                    .collect();
                (parts, merged(name), self.output.join(name))
            })
            .collect()
    }

    pub fn render_command(&self, i: usize) -> Vec<String> {
        let mut cmd = vec![
            self.lightpath.display().to_string(),
            "render".into(),
            self.scene.clone(),
        ];
        cmd.extend(self.render_args.iter().cloned());
        cmd.extend(self.parts[i].args());
        cmd.extend([
            "--quiet".into(),
            "-o".into(),
            self.part_path(i).display().to_string(),
        ]);
        cmd
    }

    /// `lightpath merge` of the parts: one command, or one per render product.
    pub fn merge_commands(&self) -> Vec<Vec<String>> {
        self.merges()
            .into_iter()
            .map(|(parts, merged, _)| {
                let mut cmd = vec![self.lightpath.display().to_string(), "merge".into()];
                cmd.extend(parts.iter().map(|p| p.display().to_string()));
                cmd.extend(["-o".into(), merged.display().to_string()]);
                cmd
            })
            .collect()
    }

    /// `lightpath denoise` of the merged frame (of each product's file), when asked.
    pub fn denoise_commands(&self) -> Vec<Vec<String>> {
        let Some(options) = self.denoise.as_ref() else {
            return Vec::new();
        };
        self.merges()
            .into_iter()
            .map(|(_, merged, out)| {
                let mut cmd = vec![
                    self.lightpath.display().to_string(),
                    "denoise".into(),
                    merged.display().to_string(),
                ];
                cmd.extend(options.iter().cloned());
                cmd.extend(["-o".into(), out.display().to_string()]);
                cmd
            })
            .collect()
    }

    fn finish_lines(&self) -> String {
        let lines: Vec<String> = self
            .merge_commands()
            .iter()
            .chain(&self.denoise_commands())
            .map(|c| quote_all(c))
            .collect();
        lines.join("\n")
    }

    fn preamble(&self, what: &str) -> String {
        format!(
            "#!/usr/bin/env bash\n# {} {}: {} as {} parts -> {}\nset -euo pipefail\nparts={}\nmkdir -p \"$parts\"\n{}",
            crate::output::software(),
            what,
            self.scene,
            self.parts.len(),
            self.output.display(),
            shell_quote(&self.parts_dir().display().to_string()),
            self.product_dirs(),
        )
    }

    /// With several products: the directories the parts, the merges and the output
    /// write into, made before any part runs.
    fn product_dirs(&self) -> String {
        if self.products.is_empty() {
            return String::new();
        }
        let mut dirs: Vec<String> = (0..self.parts.len())
            .map(|i| self.part_path(i).display().to_string())
            .collect();
        if self.denoise.is_some() {
            dirs.push(self.parts_dir().join("merged").display().to_string());
        }
        dirs.push(self.output.display().to_string());
        format!("mkdir -p {}\n", quote_all(&dirs))
    }

    /// A script that submits a job array of the parts and a merge job depending on it
    /// (`afterok`: the merge runs only if every part succeeded). It prints the two job
    /// ids; the output appears when the merge ends.
    pub fn slurm_script(&self) -> String {
        let sbatch = if self.sbatch_args.is_empty() {
            String::new()
        } else {
            format!(" {}", quote_all(&self.sbatch_args))
        };
        let mut s = self.preamble("Slurm submission");
        s.push_str(&format!(
            "array=$(sbatch --parsable{sbatch} --job-name=lightpath-parts --array=0-{} --output=\"$parts/part-%a.log\" <<'LIGHTPATH_PARTS'\n",
            self.parts.len() - 1
        ));
        s.push_str("#!/usr/bin/env bash\nset -euo pipefail\ncase \"$SLURM_ARRAY_TASK_ID\" in\n");
        for i in 0..self.parts.len() {
            s.push_str(&format!(
                "  {i}) exec {} ;;\n",
                quote_all(&self.render_command(i))
            ));
        }
        s.push_str(
            "  *) echo \"no part $SLURM_ARRAY_TASK_ID\" >&2; exit 2 ;;\nesac\nLIGHTPATH_PARTS\n)\n",
        );
        s.push_str(&format!(
            "merge=$(sbatch --parsable{sbatch} --job-name=lightpath-merge --dependency=afterok:\"${{array%%;*}}\" --output=\"$parts/merge.log\" <<'LIGHTPATH_MERGE'\n#!/usr/bin/env bash\nset -euo pipefail\n{}\nLIGHTPATH_MERGE\n)\n",
            self.finish_lines()
        ));
        s.push_str("echo \"parts: job array $array; merge: job $merge\"\n");
        s
    }

    /// A script that renders the parts with GNU `parallel` on one workstation (each part
    /// with `--threads` so the parts share the cores) and merges them.
    pub fn parallel_script(&self, jobs: u32) -> String {
        let mut s = self.preamble("GNU parallel");
        s.push_str(&format!(
            "parallel --halt now,fail=1 --jobs {jobs} ::: \\\n"
        ));
        for i in 0..self.parts.len() {
            let end = if i + 1 == self.parts.len() {
                "\n"
            } else {
                " \\\n"
            };
            s.push_str(&format!(
                "  {}{end}",
                shell_quote(&quote_all(&self.render_command(i)))
            ));
        }
        s.push_str(&format!("{}\n", self.finish_lines()));
        s
    }
}

/// `args` without option `name` and its value (`--spp 4` or `--spp=4`).
pub fn without_option(args: &[String], name: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut skip = false;
    for a in args {
        if skip {
            skip = false;
        } else if a == name {
            skip = true;
        } else if !a.starts_with(&format!("{name}=")) {
            out.push(a.clone());
        }
    }
    out
}

/// `args` without the flag `name` (an option that takes no value), however often given.
pub fn without_flag(args: &[String], name: &str) -> Vec<String> {
    args.iter().filter(|a| *a != name).cloned().collect()
}

/// Takes the render options' denoising out of a farm's shared render options: the
/// parts render noisy and only the merged frame is denoised. Returns the remaining
/// render options and, when `--denoise` was given, the `lightpath denoise` options
/// (`--keep-noisy`, `--quality Q`).
pub fn split_denoise(
    args: &[String],
    denoise: bool,
    keep_noisy: bool,
    quality: &str,
) -> (Vec<String>, Option<Vec<String>>) {
    let mut rest = without_flag(args, "--denoise");
    rest = without_flag(&rest, "--keep-noisy");
    rest = without_option(&rest, "--denoise-quality");
    let options = denoise.then(|| {
        let mut o = Vec::new();
        if keep_noisy {
            o.push("--keep-noisy".to_string());
        }
        o.extend(["--quality".to_string(), quality.to_string()]);
        o
    });
    (rest, options)
}

/// An absolute path (without resolving links), so that jobs run from any directory.
pub fn absolute(path: &Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_are_even_and_cover_everything_once() {
        let parts = split(SplitBy::Samples, 3, 8, [4, 4]).unwrap();
        assert_eq!(
            parts,
            [
                Part::Samples { first: 0, spp: 3 },
                Part::Samples { first: 3, spp: 3 },
                Part::Samples { first: 6, spp: 2 }
            ]
        );
        let tiles = split(SplitBy::Tiles, 4, 8, [10, 7]).unwrap();
        let rows: Vec<(u32, u32)> = tiles
            .iter()
            .map(|p| match p {
                Part::Tile(w) => {
                    assert_eq!((w.x0, w.x1), (0, 10));
                    (w.y0, w.y1)
                }
                _ => unreachable!(),
            })
            .collect();
        assert_eq!(rows, [(0, 2), (2, 4), (4, 6), (6, 7)]);
        assert!(split(SplitBy::Samples, 9, 8, [4, 4]).is_err());
        assert!(split(SplitBy::Tiles, 5, 8, [4, 4]).is_err());
        assert!(split(SplitBy::Tiles, 0, 8, [4, 4]).is_err());
    }

    #[test]
    fn an_option_is_removed_with_its_value() {
        let args: Vec<String> = ["--spp", "4", "--aov", "a=C<RD>L", "--spp=8", "--half"]
            .map(String::from)
            .to_vec();
        assert_eq!(
            without_option(&args, "--spp"),
            ["--aov", "a=C<RD>L", "--half"]
        );
    }

    #[test]
    fn denoising_moves_from_the_parts_to_the_merged_frame() {
        let args: Vec<String> = [
            "--denoise",
            "--spp",
            "64",
            "--keep-noisy",
            "--denoise-quality=fast",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        let (rest, denoise) = split_denoise(&args, true, true, "fast");
        assert_eq!(rest, ["--spp", "64"]);
        let denoise = denoise.unwrap();
        assert_eq!(denoise, ["--keep-noisy", "--quality", "fast"]);
        let job = FarmJob {
            lightpath: "/bin/lightpath".into(),
            scene: "cornell".into(),
            render_args: rest,
            parts: split(SplitBy::Samples, 2, 64, [32, 32]).unwrap(),
            output: "/out/shot.exr".into(),
            sbatch_args: Vec::new(),
            denoise: Some(denoise),
            products: Vec::new(),
        };
        for script in [job.slurm_script(), job.parallel_script(2)] {
            // No part denoises; the merge writes merged.exr, which is denoised into the
            // output.
            assert_eq!(script.matches("--denoise").count(), 0, "{script}");
            assert!(script.contains("merge /out/shot.parts/part-0000.exr /out/shot.parts/part-0001.exr -o /out/shot.parts/merged.exr\n/bin/lightpath denoise /out/shot.parts/merged.exr --keep-noisy --quality fast -o /out/shot.exr\n"), "{script}");
        }
        // Without --denoise nothing changes.
        let (rest, none) = split_denoise(&job.render_args, false, false, "high");
        assert_eq!((rest, none), (job.render_args.clone(), None));
        let plain = FarmJob {
            denoise: None,
            ..job.clone()
        };
        assert!(plain.parallel_script(2).ends_with("-o /out/shot.exr\n"));

        // Several render products: each part renders them into a directory of its own,
        // and each product is merged, then denoised, on its own into the output directory.
        let products = FarmJob {
            output: "/out/shots".into(),
            products: vec!["aovs.exr".into(), "beauty.exr".into()],
            ..job
        };
        let script = products.parallel_script(2);
        assert!(script.contains("mkdir -p /out/shots.parts/part-0000/ /out/shots.parts/part-0001/ /out/shots.parts/merged /out/shots\n"), "{script}");
        assert!(
            script.contains("--quiet -o /out/shots.parts/part-0001/"),
            "{script}"
        );
        for name in ["aovs", "beauty"] {
            assert!(script.contains(&format!("merge /out/shots.parts/part-0000/{name}.exr /out/shots.parts/part-0001/{name}.exr -o /out/shots.parts/merged/{name}.exr\n")), "{script}");
            assert!(script.contains(&format!("denoise /out/shots.parts/merged/{name}.exr --keep-noisy --quality fast -o /out/shots/{name}.exr")), "{script}");
        }
    }

    #[test]
    fn shell_quoting_survives_spaces_and_quotes() {
        assert_eq!(shell_quote("a/b.exr"), "a/b.exr");
        assert_eq!(shell_quote("it's here"), r"'it'\''s here'");
        assert_eq!(
            shell_quote("C<.>*[<L.'key'>O]"),
            r"'C<.>*[<L.'\''key'\''>O]'"
        );
        assert_eq!(shell_quote(""), "''");
    }
}
