//! Shots on a render farm (issue 15): `viewcloth batch SHOTS --emit slurm` writes an sbatch job
//! array, one task per shot, each running `batch SHOTS --shot-from-env SLURM_ARRAY_TASK_ID`.
//!
//! A simulation is sequential in time, so one shot is one task. Slurm sends the batch shell
//! SIGTERM 120 s before the time limit (`--signal=B:TERM@120`) or at a preemption; the script
//! passes it on to viewcloth, which checkpoints at the end of its frame and exits 75; the script
//! then requeues its own task (`--requeue` allows it), and the rerun of the same command resumes
//! the shot from its checkpoint (a finished shot is skipped).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::batch::Shot;
use crate::io::OutputFormat;

/// `--cpus-per-task` when neither `--threads` nor `SLURM_CPUS_PER_TASK` gives one.
pub const DEFAULT_CPUS_PER_TASK: u64 = 4;

/// What `emit_slurm` wrote.
pub struct Emitted {
    pub script: PathBuf,
    pub commands: PathBuf,
}

/// A word quoted for a POSIX shell.
fn sh(word: &str) -> String {
    if !word.is_empty() && word.bytes().all(|b| b.is_ascii_alphanumeric() || b"/._-+=:,@".contains(&b)) {
        return word.to_string();
    }
    format!("'{}'", word.replace('\'', r"'\''"))
}

fn absolute(p: &Path) -> Result<PathBuf, String> {
    std::path::absolute(p).map_err(|e| format!("{}: {e}", p.display()))
}

/// Writes `DIR/<stem>.sbatch` (the array job) and `DIR/<stem>.commands` (each task's command
/// line, resolved, with the shot it runs), and creates `DIR/logs/` for the per-task logs.
/// `format` is `batch --format`, passed on to the tasks (omitted when the default, `obj`).
pub fn emit_slurm(
    shots_file: &Path,
    shots: &[Shot],
    dir: &Path,
    cpus: u64,
    format: OutputFormat,
) -> Result<Emitted, String> {
    let stem = shots_file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "shots".into());
    let exe = std::env::current_exe().map_err(|e| format!("cannot find the viewcloth binary: {e}"))?;
    let shots_abs = absolute(shots_file)?;
    let cwd = absolute(Path::new("."))?;
    std::fs::create_dir_all(dir.join("logs")).map_err(|e| format!("{}: {e}", dir.display()))?;
    let dir_abs = absolute(dir)?;
    let logs = dir_abs.join("logs");
    let n = shots.len();
    // `which`: `--shot I` (the commands file) or `--shot-from-env SLURM_ARRAY_TASK_ID` (the
    // script); `index`: the shell word of the index in the summary's name.
    let command = |which: &str, index: &str| {
        let summary = dir_abs.join(format!("{stem}.shot"));
        let format = match format {
            OutputFormat::Obj => String::new(),
            f => format!(" --format {}", f.name()),
        };
        format!(
            "{} batch {} {which} --threads {cpus} --progress lines --summary {}{index}.batch.json{format}",
            sh(&exe.to_string_lossy()),
            sh(&shots_abs.to_string_lossy()),
            sh(&summary.to_string_lossy()),
        )
    };
    let mut script = String::new();
    let _ = writeln!(script, "#!/bin/bash");
    let _ = writeln!(
        script,
        "# Written by `viewcloth batch {} --emit slurm`: one array task per shot.",
        shots_file.display()
    );
    let _ = writeln!(script, "# Submit with: sbatch {}", dir_abs.join(format!("{stem}.sbatch")).display());
    let job: String = stem.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' { c } else { '_' }).collect();
    let _ = writeln!(script, "#SBATCH --job-name=viewcloth-{job}");
    let _ = writeln!(script, "#SBATCH --array=0-{}", n - 1);
    let _ = writeln!(script, "#SBATCH --cpus-per-task={cpus}");
    let _ = writeln!(script, "#SBATCH --ntasks=1");
    let _ = writeln!(script, "#SBATCH --requeue");
    let _ = writeln!(script, "#SBATCH --signal=B:TERM@120");
    let _ = writeln!(script, "#SBATCH --open-mode=append");
    let _ = writeln!(script, "#SBATCH --output={}", logs.join("%x_%A_%a.log").display());
    let _ = writeln!(script, "#SBATCH --chdir={}", cwd.display());
    script.push_str(&format!(
        r#"
# SIGTERM (the time limit's --signal, a preemption, scancel --signal=TERM) goes to this shell
# (B:); it is passed on to viewcloth, which finishes its frame, checkpoints and exits 75. The
# task then requeues itself, and the same command resumes the shot from its checkpoint.
task="${{SLURM_ARRAY_JOB_ID}}_${{SLURM_ARRAY_TASK_ID}}"
echo "viewcloth: task $task (restart ${{SLURM_RESTART_COUNT:-0}}) on $(hostname) at $(date -u +%FT%TZ)"
{} &
child=$!
trap 'kill -TERM "$child" 2>/dev/null' TERM INT
wait "$child"; rc=$?
# wait returns early (status > 128) when the trap ran: wait for viewcloth itself (bash keeps its
# status; 127 once it was taken).
while [ "$rc" -gt 128 ]; do wait "$child"; next=$?; [ "$next" -eq 127 ] && break; rc=$next; done
echo "viewcloth: task $task exit $rc at $(date -u +%FT%TZ)"
if [ "$rc" -eq 75 ]; then
    echo "viewcloth: interrupted at a checkpoint; requeueing $task"
    scontrol requeue "$task"
fi
exit "$rc"
"#,
        command("--shot-from-env SLURM_ARRAY_TASK_ID", "\"${SLURM_ARRAY_TASK_ID}\"")
    ));
    let mut commands = String::new();
    let _ = writeln!(commands, "# Task I of the array runs, from {}:", cwd.display());
    for (i, shot) in shots.iter().enumerate() {
        let _ = writeln!(
            commands,
            "# shot {i}: {} ({} frames) -> {}",
            shot.scene_file.display(),
            shot.last_frame(),
            shot.out.display()
        );
        let _ = writeln!(commands, "{}", command(&format!("--shot {i}"), &i.to_string()));
    }
    let script_path = dir.join(format!("{stem}.sbatch"));
    let commands_path = dir.join(format!("{stem}.commands"));
    crate::io::write_atomic(&script_path, script.as_bytes()).map_err(|e| format!("{}: {e}", script_path.display()))?;
    crate::io::write_atomic(&commands_path, commands.as_bytes())
        .map_err(|e| format!("{}: {e}", commands_path.display()))?;
    Ok(Emitted { script: script_path, commands: commands_path })
}
