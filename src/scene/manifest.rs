//! Manifests of scenes for batch bakes on clusters without a scheduler of
//! our own (Slurm job arrays, Kubernetes indexed jobs): a text file, one
//! scene path per line, relative to the manifest's folder; blank lines and
//! lines starting with # are skipped. Task N bakes the N-th scene (from 0,
//! as SLURM_ARRAY_TASK_ID=0.. and JOB_COMPLETION_INDEX count) into its own
//! folder, named after the scene file.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// The scenes a manifest lists, in order, resolved against its folder.
pub fn scenes(manifest: &Path) -> Result<Vec<PathBuf>> {
    let text = std::fs::read_to_string(manifest).map_err(|e| Error::io(manifest, e))?;
    let dir = manifest.parent().unwrap_or(Path::new("."));
    let scenes: Vec<PathBuf> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(|l| dir.join(l))
        .collect();
    if scenes.is_empty() {
        return Err(Error::format(
            manifest,
            "lists no scene (one path per line)",
        ));
    }
    Ok(scenes)
}

/// The `index`-th scene of the manifest and the folder it bakes into
/// under `out`.
pub fn entry(manifest: &Path, index: usize, out: &Path) -> Result<(PathBuf, PathBuf)> {
    let scenes = scenes(manifest)?;
    let scene = scenes.get(index).ok_or_else(|| {
        Error::format(
            manifest,
            format!(
                "has {} scenes (indices 0 to {}), no index {index}",
                scenes.len(),
                scenes.len() - 1
            ),
        )
    })?;
    Ok((scene.clone(), out.join(output_name(scene))))
}

/// The folder a scene bakes into in a batch: its file name without the
/// extension.
pub fn output_name(scene: &Path) -> String {
    scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".to_string())
}
