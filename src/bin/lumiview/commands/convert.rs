//! `lumiview convert`: IES LM-63-2019 ↔ EULUMDAT (`photometry::convert`), and a near-field scan
//! (pack, manifest or ray file) → its far field as IES or EULUMDAT (`nearfield::farfield`). One input writes the
//! named file; several inputs or a folder write into an output folder and print one table (CSV, or
//! JSON lines with `--json`), continuing past a file that cannot be read. What the target format
//! cannot keep is listed on stderr.

use std::path::{Path, PathBuf};

use clap::Args;
use lumiview::photometry::convert::{to_ies, to_ldt, Converted};
use lumiview::photometry::{FileFormat, Photometry};
use serde_json::json;

use super::{csv_row, expand_inputs, load_quiet, print_report, CliResult};
use crate::LoadArgs;

/// Arguments of `lumiview convert`.
#[derive(Args, Debug)]
pub struct ConvertArgs {
    /// IES (.ies) or EULUMDAT (.ldt) files, or folders of them; or a near-field scan (.lvpack,
    /// scan manifest, TM-25 ray file), written as its far field estimated from its images.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Output: a file ending in .ies or .ldt for one input, or a folder (created if missing) for
    /// several inputs or a folder.
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    /// Target format when writing into a folder: `ies` or `ldt` (default: the other format of
    /// each input).
    #[arg(long, value_name = "ies|ldt")]
    pub to: Option<String>,
    /// Several inputs: print the table as JSON lines instead of CSV.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub load: LoadArgs,
}

/// The target format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Target {
    Ies,
    Ldt,
}

impl Target {
    fn ext(self) -> &'static str {
        match self {
            Target::Ies => "ies",
            Target::Ldt => "ldt",
        }
    }

    fn of_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "ies" => Some(Target::Ies),
            "ldt" => Some(Target::Ldt),
            _ => None,
        }
    }
}

/// Reads an input: photometry with the load options, or a near-field scan (pack, manifest, ray
/// file) as its far field estimated from its images (`nearfield::farfield`, progress on stderr).
fn load_input(path: &Path, args: &LoadArgs) -> Result<Photometry, Box<dyn std::error::Error>> {
    let kind = lumiview::source::detect(path)?;
    if kind.is_scan() {
        return Ok(super::scene::scan_light(path, kind)?.0);
    }
    load_quiet(path, args)
}

fn convert_one(p: &Photometry, target: Target, out: &Path) -> Result<Converted, Box<dyn std::error::Error>> {
    let name = out
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    Ok(match target {
        Target::Ies => to_ies(p)?,
        Target::Ldt => to_ldt(p, &name)?,
    })
}

/// Writes `text` to `out` through a uniquely named temporary file beside it
/// ([`lumiview::files::TempOutput`]), so a failed or interrupted write leaves no half-written file;
/// refuses to replace the input it was made from.
fn write_output(input: &Path, out: &Path, text: &str) -> Result<(), String> {
    use std::io::Write as _;
    if lumiview::files::same_file(input, out) {
        return Err(format!(
            "{}: the output is the input file itself; choose another output name",
            out.display()
        ));
    }
    let (mut tmp, _) =
        lumiview::files::TempOutput::create(out).map_err(|e| format!("{}: cannot write: {e}", out.display()))?;
    let cannot = |e: std::io::Error| format!("{}: cannot write: {e}", out.display());
    if let Some(f) = tmp.file() {
        f.write_all(text.as_bytes()).map_err(cannot)?;
    }
    tmp.commit().map_err(cannot)
}

/// `lumiview convert`.
pub fn convert(a: &ConvertArgs) -> CliResult {
    let forced =
        a.to.as_deref()
            .map(|t| match t.to_ascii_lowercase().as_str() {
                "ies" => Ok(Target::Ies),
                "ldt" => Ok(Target::Ldt),
                _ => Err(format!("--to `{t}`: expected ies or ldt")),
            })
            .transpose()?;
    let inputs = expand_inputs(&a.files)?;
    let several = inputs.len() > 1 || a.files.iter().any(|f| f.is_dir());
    // Outputs never replace inputs: every input, by its canonical path.
    let protected: Vec<PathBuf> = inputs.iter().filter_map(|p| std::fs::canonicalize(p).ok()).collect();
    let is_input = |out: &Path| std::fs::canonicalize(out).ok().is_some_and(|c| protected.contains(&c));
    if !several && !a.output.is_dir() {
        let target = Target::of_path(&a.output).ok_or_else(|| {
            format!(
                "{}: the output must end in .ies or .ldt (or be a folder)",
                a.output.display()
            )
        })?;
        if forced.is_some_and(|t| t != target) {
            return Err(format!(
                "--to {}: the output {} names the other format",
                a.to.as_deref().unwrap_or(""),
                a.output.display()
            )
            .into());
        }
        let p = load_input(&inputs[0], &a.load)?;
        for w in &p.warnings {
            eprintln!("lumiview: warning: {w}");
        }
        let c = convert_one(&p, target, &a.output)?;
        if is_input(&a.output) {
            return Err(format!(
                "{}: the output is the input file itself; choose another output name",
                a.output.display()
            )
            .into());
        }
        write_output(&inputs[0], &a.output, &c.text)?;
        for l in &c.lost {
            eprintln!("lumiview: not kept: {l}");
        }
        return print_report(&format!(
            "{}: {} → {} ({} item(s) not kept{})\n",
            a.output.display(),
            p.format.name(),
            match target {
                Target::Ies => "IES LM-63-2019",
                Target::Ldt => "EULUMDAT",
            },
            c.lost.len(),
            if c.lost.is_empty() { "" } else { ", listed on stderr" }
        ));
    }
    if a.output.exists() && !a.output.is_dir() {
        return Err(format!(
            "{}: with several inputs or a folder the output must be a folder",
            a.output.display()
        )
        .into());
    }
    std::fs::create_dir_all(&a.output).map_err(|e| format!("{}: cannot create the folder: {e}", a.output.display()))?;
    let mut out = String::new();
    if !a.json {
        outln!(out, "input,output,format,not_kept,error");
    }
    let mut written: Vec<(PathBuf, PathBuf)> = Vec::new();
    let mut failed = 0usize;
    for input in &inputs {
        let result = (|| -> Result<(PathBuf, Converted, Target), Box<dyn std::error::Error>> {
            let p = load_input(input, &a.load)?;
            for w in &p.warnings {
                eprintln!("lumiview: warning: {w}");
            }
            let target = forced.unwrap_or(match p.format {
                FileFormat::Eulumdat => Target::Ies,
                FileFormat::Ies(_) => Target::Ldt,
            });
            let stem = input
                .file_stem()
                .map_or_else(|| "out".into(), |s| s.to_string_lossy().into_owned());
            let path = a.output.join(format!("{stem}.{}", target.ext()));
            if let Some((_, from)) = written.iter().find(|(o, _)| *o == path) {
                return Err(format!(
                    "{} was already written from {} in this run; rename one of the inputs",
                    path.display(),
                    from.display()
                )
                .into());
            }
            if is_input(&path) {
                return Err(format!(
                    "{} is one of the inputs of this run and is not replaced (write into another folder)",
                    path.display()
                )
                .into());
            }
            let c = convert_one(&p, target, &path)?;
            write_output(input, &path, &c.text)?;
            Ok((path, c, target))
        })();
        match result {
            Ok((path, c, target)) => {
                for l in &c.lost {
                    eprintln!("lumiview: not kept ({}): {l}", input.display());
                }
                if a.json {
                    outln!(
                        out,
                        "{}",
                        json!({"input": input.display().to_string(), "output": path.display().to_string(),
                               "format": target.ext(), "not_kept": c.lost})
                    );
                } else {
                    outln!(
                        out,
                        "{}",
                        csv_row([
                            input.display().to_string(),
                            path.display().to_string(),
                            target.ext().to_string(),
                            c.lost.join("; "),
                            String::new(),
                        ])
                    );
                }
                written.push((path, input.clone()));
            }
            Err(e) => {
                failed += 1;
                eprintln!("lumiview: error: {}: {e}", input.display());
                if a.json {
                    outln!(
                        out,
                        "{}",
                        json!({"input": input.display().to_string(), "error": e.to_string()})
                    );
                } else {
                    outln!(
                        out,
                        "{}",
                        csv_row([
                            input.display().to_string(),
                            String::new(),
                            String::new(),
                            String::new(),
                            e.to_string()
                        ])
                    );
                }
            }
        }
    }
    print_report(&out)?;
    if failed > 0 {
        return Err(format!(
            "{failed} of {} files could not be converted (named above)",
            inputs.len()
        )
        .into());
    }
    Ok(())
}
