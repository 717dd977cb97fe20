//! A bake's unwraps kept for the next bake into the same folder (issue
//! 38): a facet's cut and flattening depend on its piece of the mesh, what
//! the scene's viewpoints see of it, the unwrap's settings and the code,
//! not on its tissue or texture transform. Beside the outputs, under
//! DIR/unwraps/, each facet's uv layer and figures go with a digest of
//! those (`key`); a bake whose key for the facet is the same takes them
//! instead of unwrapping again (the same uvs it would make), so a
//! clinician who changes a tissue waits for the textures alone.
//!
//! JSON, with serde_json's exact float round trip (Cargo.toml), so the uvs
//! read back are the bits written; a file that does not parse, or names
//! another key, is not used.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::atomic::write_file;
use crate::digest::Digest;
use crate::error::{Error, Result};
use crate::mesh::{TriMesh, UvLayer};
use crate::unwrap::UnwrapOptions;
use crate::unwrap::flatten::Method;
use crate::unwrap::metrics::UvMetrics;
use crate::unwrap::visibility::Visibility;

/// The folder under a bake's output folder that keeps its unwraps.
pub const FOLDER: &str = "unwraps";

/// What a bake keeps of one facet's unwrap: the uv layer and the figures
/// report.json gives for it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct KeptUnwrap {
    pub key: String,
    pub uvs: UvLayer,
    pub seam_edges: usize,
    pub metrics: UvMetrics,
    pub flattening: Vec<Method>,
}

/// The file of node `node`'s facet `facet` under `dir` (the output
/// folder): by index, since names may hold any character.
pub fn path(dir: &Path, node: usize, facet: u32) -> PathBuf {
    dir.join(FOLDER).join(format!("{node}-{facet}.json"))
}

/// A digest of everything a facet piece's unwrap is made from: the code
/// (the library's source digest, from build.rs), the piece's mesh, what the
/// viewpoints see of it and the unwrap's options (all of them, by their
/// `Debug` text, whose floats print exactly).
pub fn key(mesh: &TriMesh, seen: &Visibility, opts: &UnwrapOptions) -> String {
    let mut digest = Digest::default();
    digest.feed(env!("ORGANTEX_SOURCE_DIGEST").as_bytes());
    digest.feed(format!("{opts:?}").as_bytes());
    mesh.feed_geometry(&mut digest);
    for x in seen.vertex.iter().chain(&seen.edge) {
        digest.feed(&x.to_le_bytes());
    }
    digest.feed(&(seen.views as u64).to_le_bytes());
    digest.hex()
}

/// The unwrap kept at `path` if it was made from `key` and fits a piece
/// of `faces` faces (a uv triangle each, naming uvs it holds: a file
/// edited by hand is not taken).
pub fn load(path: &Path, key: &str, faces: usize) -> Option<KeptUnwrap> {
    let text = std::fs::read(path).ok()?;
    let kept: KeptUnwrap = serde_json::from_slice(&text).ok()?;
    let uvs = &kept.uvs;
    let fits = uvs.triangles.len() == faces
        && uvs
            .triangles
            .iter()
            .flatten()
            .all(|&i| (i as usize) < uvs.coords.len());
    (kept.key == key && fits).then_some(kept)
}

/// Keep `kept` at `path` (written whole or not at all).
pub fn save(path: &Path, kept: &KeptUnwrap) -> Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    write_file(path, |w| {
        serde_json::to_writer(&mut *w, kept).map_err(std::io::Error::other)
    })
}

/// Remove the kept unwraps under `dir` that are not among `current` (a
/// facet or node gone from the scene): files named as `path` names them
/// only, so nothing else a user put there goes.
pub fn prune(dir: &Path, current: &[PathBuf]) -> Result<()> {
    let folder = dir.join(FOLDER);
    let Ok(entries) = std::fs::read_dir(&folder) else {
        return Ok(());
    };
    let ours = |name: &str| {
        name.strip_suffix(".json")
            .and_then(|stem| stem.split_once('-'))
            .is_some_and(|(node, facet)| {
                [node, facet]
                    .iter()
                    .all(|s| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()))
            })
    };
    for entry in entries.flatten() {
        let p = entry.path();
        let named = p.file_name().and_then(|n| n.to_str()).is_some_and(ours);
        if named && !current.contains(&p) {
            std::fs::remove_file(&p).map_err(|e| Error::io(&p, e))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The uvs come back bit for bit, and a file of another key or a
    /// broken one is not taken.
    #[test]
    fn a_kept_unwrap_reads_back_exactly_and_only_for_its_key() {
        let dir = tempfile::tempdir().unwrap();
        let kept = KeptUnwrap {
            key: "k1".into(),
            // Floats whose shortest decimal form a lax parser misreads.
            uvs: UvLayer {
                coords: vec![
                    glam::DVec2::new(0.1 + 0.2, 1.0 / 3.0),
                    glam::DVec2::new(2.225073858507201e-308, 0.7),
                ],
                triangles: vec![[0, 1, 0]],
            },
            seam_edges: 3,
            metrics: UvMetrics {
                charts: 1,
                flips: 0,
                overlaps: 0,
                degenerate: 0,
                conf_mean: 1.0123456789012345,
                area_log: 0.031,
                seam_length: 12.5,
                seam_ratio: 0.25,
                seam_vis: 0.0,
            },
            flattening: Vec::new(),
        };
        let p = path(dir.path(), 0, 2);
        save(&p, &kept).unwrap();
        let back = load(&p, "k1", 1).unwrap();
        assert_eq!(back, kept);
        for (a, b) in back.uvs.coords.iter().zip(&kept.uvs.coords) {
            assert_eq!(
                a.to_array().map(f64::to_bits),
                b.to_array().map(f64::to_bits)
            );
        }
        assert!(load(&p, "k2", 1).is_none());
        // Another piece's face count, or a uv index past the uvs: not taken.
        assert!(load(&p, "k1", 2).is_none());
        let mut broken = kept.clone();
        broken.uvs.triangles[0][2] = 2;
        save(&p, &broken).unwrap();
        assert!(load(&p, "k1", 1).is_none());
        std::fs::write(&p, b"{\"key\": \"k1\", ").unwrap();
        assert!(load(&p, "k1", 1).is_none());
        // Pruning keeps the current files, and files it did not name.
        let other = path(dir.path(), 1, 0);
        save(&other, &kept).unwrap();
        let users = dir.path().join(FOLDER).join("notes.json");
        std::fs::write(&users, b"{}").unwrap();
        prune(dir.path(), std::slice::from_ref(&p)).unwrap();
        assert!(p.is_file() && !other.exists() && users.is_file());
    }
}
