//! Input and run options shared by every command that triangulates (`tin`, and the terrain
//! products): the files, the lidar filters, duplicates, memory budget, temporary directory,
//! progress and the JSON summary.

use super::info::FilterArgs;
use std::path::PathBuf;
use sweeptin::pipeline::{DEFAULT_MEM, Input, RunOptions};

/// Input files and how to read and run them (flattened into each command's arguments).
#[derive(clap::Args, Debug, Clone)]
pub struct InputArgs {
    /// Input points: LAS/LAZ files (adjacent tiles form one point set), XYZ text files
    /// (`x y z` per line), or one streaming mesh (.stin) written by `sweeptin tin`.
    #[arg(required = true, value_name = "FILES")]
    pub inputs: Vec<PathBuf>,
    #[command(flatten)]
    pub filter: FilterArgs,
    /// Which point survives among exact (x, y) duplicates.
    #[arg(long, value_enum, default_value_t = sweeptin::DuplicatePolicy::First)]
    pub duplicates: sweeptin::DuplicatePolicy,
    /// Memory budget for sorting (e.g. 512M, 4G). Larger inputs are sorted in chunks spilled to
    /// --tmp-dir; the result is the same whatever the budget.
    #[arg(long, value_name = "SIZE", default_value = "1G", value_parser = parse_size)]
    pub mem: u64,
    /// Directory for spill files (anonymous temporary files, never left behind).
    #[arg(long, value_name = "DIR")]
    pub tmp_dir: Option<PathBuf>,
    /// No progress bar.
    #[arg(short, long)]
    pub quiet: bool,
    /// Print a one-object JSON summary on stdout (points, triangles, seconds per phase, peak
    /// memory) for batch jobs.
    #[arg(long)]
    pub json: bool,
}

impl InputArgs {
    /// The library's description of the input.
    pub fn input(&self) -> Input {
        Input {
            paths: self.inputs.clone(),
            filter: self.filter.to_filter(),
            duplicates: self.duplicates,
        }
    }

    /// The library's run options.
    pub fn options(&self) -> RunOptions {
        RunOptions {
            mem: self.mem,
            tmp_dir: self.tmp_dir.clone(),
            progress: !self.quiet && !self.json,
        }
    }
}

/// Parses a human size: `1048576`, `512K`, `128M`, `4G`, `1T`, optionally with `B`, `iB` or a
/// space (binary multiples: 1K = 1024).
pub fn parse_size(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let v: f64 = num
        .parse()
        .map_err(|_| format!("'{s}' is not a size like 512M or 4G"))?;
    let mult: u64 = match unit.trim().to_ascii_uppercase().as_str() {
        "" | "B" => 1,
        "K" | "KB" | "KIB" => 1 << 10,
        "M" | "MB" | "MIB" => 1 << 20,
        "G" | "GB" | "GIB" => 1 << 30,
        "T" | "TB" | "TIB" => 1 << 40,
        _ => {
            return Err(format!(
                "'{s}': unknown size unit '{unit}' (use K, M, G or T)"
            ));
        }
    };
    let bytes = v * mult as f64;
    if !(1.0..=1e18).contains(&bytes) {
        return Err(format!("'{s}' is not a sensible memory size"));
    }
    Ok(bytes as u64)
}

#[allow(dead_code)]
const _DEFAULT_IS_1G: () = assert!(DEFAULT_MEM == 1 << 30);

#[cfg(test)]
mod tests {
    #[test]
    fn sizes() {
        use super::parse_size;
        assert_eq!(parse_size("512M"), Ok(512 << 20));
        assert_eq!(parse_size("4G"), Ok(4 << 30));
        assert_eq!(parse_size("1.5K"), Ok(1536));
        assert_eq!(parse_size("100"), Ok(100));
        assert_eq!(parse_size("128 MiB"), Ok(128 << 20));
        assert!(parse_size("lots").is_err());
        assert!(parse_size("5X").is_err());
    }
}
