//! `lumiview solid`: the photometric solid (r = scale · I / I_max) as Wavefront OBJ (luminaire
//! frame, Z up) or glTF 2.0 binary (Y up: (x, y, z) → (x, z, −y)). See docs/lut-and-solid.md.

use std::path::{Path, PathBuf};

use lumiview::photometry::solid::{PhotometricSolid, SolidOptions};

use super::{print_report, CliResult};

/// Arguments of `lumiview solid`.
#[derive(clap::Args, Debug)]
pub struct SolidArgs {
    /// IES or EULUMDAT file.
    pub file: PathBuf,
    /// Output file: .obj or .glb.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Radius in metres at the maximum intensity.
    #[arg(long, value_name = "M", default_value_t = 1.0)]
    pub scale: f64,
    /// Mesh resolution: C steps x γ steps (360°/C and 180°/G apart).
    #[arg(long, value_name = "CxG", default_value = "72x36")]
    pub resolution: String,
    #[command(flatten)]
    pub load: crate::LoadArgs,
}

/// Output container.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum MeshFormat {
    Obj,
    Glb,
}

fn mesh_format(path: &Path) -> Result<MeshFormat, String> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("obj") => Ok(MeshFormat::Obj),
        Some("glb") => Ok(MeshFormat::Glb),
        _ => Err(format!(
            "{}: unknown output extension; expected .obj or .glb",
            path.display()
        )),
    }
}

fn parse_resolution(text: &str) -> Result<(usize, usize), String> {
    let bad = || format!("--resolution `{text}`: expected CxG (C steps x γ steps), e.g. 72x36");
    let (c, g) = text.split_once(['x', 'X', '×']).ok_or_else(bad)?;
    let c = c.trim().parse::<usize>().map_err(|_| bad())?;
    let g = g.trim().parse::<usize>().map_err(|_| bad())?;
    Ok((c, g))
}

/// Runs `lumiview solid`.
pub fn solid(args: &SolidArgs) -> CliResult {
    let format = mesh_format(&args.output)?;
    let (c_steps, gamma_steps) = parse_resolution(&args.resolution)?;
    let p = super::load(&args.file, &args.load)?;
    let opts = SolidOptions {
        c_steps,
        gamma_steps,
        scale_m: args.scale,
    };
    let mesh = PhotometricSolid::new(&p.web, &opts).map_err(|e| format!("{}: {e}", args.file.display()))?;
    let bytes = match format {
        MeshFormat::Obj => mesh.to_obj().into_bytes(),
        MeshFormat::Glb => mesh.to_glb().map_err(|e| format!("{}: {e}", args.output.display()))?,
    };
    std::fs::write(&args.output, bytes).map_err(|e| format!("{}: cannot write file: {e}", args.output.display()))?;
    let (lo, hi) = mesh.bounds();
    let frame = match format {
        MeshFormat::Obj => "luminaire frame, Z up, nadir along -Z, C0 along +X",
        MeshFormat::Glb => "glTF Y up, (x, y, z) -> (x, z, -y): nadir along -Y, C0 along +X, C90 along -Z",
    };
    let text = format!(
        "wrote {}: photometric solid of {}\n\
         mesh: {c_steps} C steps x {gamma_steps} gamma steps, {} vertices, {} triangles\n\
         radius: {} m at max_cd {} cd\n\
         bounds (luminaire frame, m): x {}..{}, y {}..{}, z {}..{}\n\
         frame: {frame}\n",
        args.output.display(),
        p.source,
        mesh.vertex_count(),
        mesh.triangle_count(),
        args.scale,
        mesh.max_cd(),
        lo[0],
        hi[0],
        lo[1],
        hi[1],
        lo[2],
        hi[2]
    );
    print_report(&text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_and_resolutions() {
        assert_eq!(mesh_format(Path::new("a.OBJ")), Ok(MeshFormat::Obj));
        assert_eq!(mesh_format(Path::new("a.glb")), Ok(MeshFormat::Glb));
        assert!(mesh_format(Path::new("a.gltf")).is_err());
        assert!(mesh_format(Path::new("a")).is_err());
        assert_eq!(parse_resolution("72x36"), Ok((72, 36)));
        assert!(parse_resolution("72").is_err());
        assert!(parse_resolution("ax3").is_err());
    }
}
