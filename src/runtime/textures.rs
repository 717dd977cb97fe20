//! Texture for any new faces a simulator makes (a curved incision, a
//! resected wall): triangles in the organ's rest frame in, each a chart in
//! a cut-texture atlas out, its texels coloured from the node's interior
//! at their 3D points. Carving (`runtime::carving`) does the same for tet
//! faces, where the tet is known.

use std::sync::Arc;

use glam::DVec3;
use rayon::prelude::*;

use super::atlas::{AtlasOptions, CutAtlas, Rect};
use super::bake::{Node, check_points};
use crate::error::{Error, Result};

/// A chart made for one triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placed {
    /// The chart's id, to release it.
    pub chart: u32,
    pub page: u32,
    /// The corners' texture coordinates in the page (0..1, v down).
    pub uvs: [[f32; 2]; 3],
}

/// An atlas of new faces' textures over one node.
pub struct CutTextures {
    node: Arc<Node>,
    atlas: CutAtlas,
}

impl CutTextures {
    pub fn new(node: Arc<Node>, options: AtlasOptions) -> Result<CutTextures> {
        Ok(CutTextures {
            node,
            atlas: CutAtlas::new(options)?,
        })
    }

    pub fn atlas(&self) -> &CutAtlas {
        &self.atlas
    }

    /// Charts for `triangles` (corners in the organ's rest frame), their
    /// texels filled. Refuses, adding nothing, a corner that is not finite
    /// and a triangle larger than a page.
    pub fn add(&mut self, triangles: &[[DVec3; 3]]) -> Result<Vec<Placed>> {
        let flat: Vec<DVec3> = triangles.iter().flatten().copied().collect();
        check_points(&flat).map_err(|e| match e {
            Error::Invalid { msg, .. } => Error::invalid(format!("triangle corners: {msg}")),
            e => e,
        })?;
        let mut placed = Vec::with_capacity(triangles.len());
        let mut charts = Vec::with_capacity(triangles.len());
        for (i, t) in triangles.iter().enumerate() {
            match self.atlas.add(self.atlas.flatten(*t)) {
                Ok((id, chart)) => {
                    placed.push(Placed {
                        chart: id,
                        page: chart.page,
                        uvs: chart.uvs(self.atlas.options().page_size),
                    });
                    charts.push(chart);
                }
                Err(e) => {
                    for p in &placed {
                        self.atlas.remove(p.chart)?;
                    }
                    self.atlas.take_released();
                    return Err(Error::invalid(format!("triangle {i}: {e}")));
                }
            }
        }
        let model = self.node.model();
        let texels: Vec<Vec<u8>> = charts
            .par_iter()
            .zip(triangles)
            .map(|(chart, corners)| model.face_texels(chart, *corners, None))
            .collect();
        for (chart, rgba) in charts.iter().zip(&texels) {
            self.atlas.write(chart, rgba);
        }
        Ok(placed)
    }

    /// Give back the charts `ids` (their faces vanished). Refuses, giving
    /// back none, an id that is not a live chart.
    pub fn release(&mut self, ids: &[u32]) -> Result<()> {
        let mut seen = ids.to_vec();
        seen.sort_unstable();
        if let Some(w) = seen.windows(2).find(|w| w[0] == w[1]) {
            return Err(Error::invalid(format!("chart {} is given twice", w[0])));
        }
        if let Some(&id) = ids.iter().find(|&&id| self.atlas.chart(id).is_none()) {
            return Err(Error::invalid(format!("chart {id} is not in the atlas")));
        }
        for &id in ids {
            self.atlas.remove(id)?;
        }
        Ok(())
    }

    /// Each page's rectangle written since the last call.
    pub fn take_dirty(&mut self) -> Vec<(u32, Rect)> {
        self.atlas.take_dirty()
    }

    /// Pages released since the last call.
    pub fn take_released(&mut self) -> Vec<u32> {
        self.atlas.take_released()
    }
}
