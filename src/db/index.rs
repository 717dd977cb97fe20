//! The tissue database's index: `database/index.toml`, one `[[tissue]]`
//! table per entry. Unknown keys and bad values are errors that name the
//! key and the line.
//!
//! ```toml
//! [[tissue]]
//! id = "fundus-tissue"              # unique, used by scenes
//! name = "Fundus tissue"
//! kind = "retina"                   # tissue kind, free text
//! shelf = "surface"                 # optional: surface, interior or
//!                                   # overlay, the viewer's shelf it is
//!                                   # shown on (default: overlay for an
//!                                   # overlay-only entry, interior for
//!                                   # layers without colour, else
//!                                   # surface)
//! source = "sources/retina.jpg"     # relative to the database folder
//! crop = { x = 250, y = 250, width = 900, height = 900 }   # optional
//! mask = "masks/x.png"              # optional: white usable
//! mask_rules = ["dark", "bright", "vessels"]              # optional
//! lighting = "flatten"              # optional: divide out uneven lighting
//! licence = "CC BY 4.0"             # optional: the source's licence
//! credit = "..."                    # optional: its credit line
//! outputs = ["colour", "height"]    # colour, height, overlay, layers
//!                                   # (overlay: a tileable vessel tree
//!                                   # in the photo's vessel colour and
//!                                   # coverage, `synth::vessel_tree`;
//!                                   # layers: the crop itself, its rows
//!                                   # depths, for layered interiors)
//! [tissue.synthesis]                # for colour and height
//! width = 512
//! height = 512
//! seed = 1
//! iterations = 3
//! neighbourhood = 7
//! tileable = true
//! occurrence = 0.1                  # FNPTS's occurrence penalty (default 0.1)
//! ```

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::synth::exemplar::Crop;
use crate::synth::mask::MaskRule;

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct IndexFile {
    #[serde(default)]
    tissue: Vec<Tissue>,
}

/// What a database entry produces.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Output {
    /// The tileable colour texture (FNPTS).
    Colour,
    /// Its height map, 16-bit, synthesised jointly.
    Height,
    /// An RGBA vessel overlay from the (cropped) photograph.
    Overlay,
    /// A layered exemplar, rows = depth, top = outer: the crop as prepared
    /// (lighting flattened where asked, mask in the alpha channel), not
    /// resynthesised, for interiors layered by depth (`[node.interior]
    /// method = "layered"`, seed 002, 4.2).
    Layers,
}

impl Output {
    /// As `outputs` in index.toml names it.
    pub fn name(self) -> &'static str {
        match self {
            Output::Colour => "colour",
            Output::Height => "height",
            Output::Overlay => "overlay",
            Output::Layers => "layers",
        }
    }

    pub fn file_name(self) -> &'static str {
        match self {
            Output::Colour => "colour.png",
            Output::Height => "height.png",
            Output::Overlay => "overlay.png",
            Output::Layers => "layers.png",
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SynthesisParams {
    pub width: usize,
    pub height: usize,
    #[serde(default)]
    pub seed: u64,
    #[serde(default = "default_iterations")]
    pub iterations: usize,
    #[serde(default = "default_neighbourhood")]
    pub neighbourhood: usize,
    #[serde(default = "default_true")]
    pub tileable: bool,
    /// FNPTS's occurrence penalty (`SynthOptions::occurrence`): heavier
    /// for a small exemplar whose copies lock into a lattice of repeats.
    #[serde(default = "default_occurrence")]
    pub occurrence: f64,
}

fn default_occurrence() -> f64 {
    crate::synth::fnpts::SynthOptions::default().occurrence
}

fn default_iterations() -> usize {
    3
}
fn default_neighbourhood() -> usize {
    7
}
fn default_true() -> bool {
    true
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tissue {
    pub id: String,
    pub name: String,
    pub kind: String,
    pub source: PathBuf,
    #[serde(default)]
    pub crop: Option<Crop>,
    #[serde(default)]
    pub mask: Option<PathBuf>,
    #[serde(default)]
    pub mask_rules: Vec<MaskRule>,
    pub outputs: Vec<Output>,
    #[serde(default)]
    pub synthesis: Option<SynthesisParams>,
    /// "flatten": divide out uneven lighting (an endoscope's cone of
    /// light) before synthesis, `synth::lighting`; "keep" (the default)
    /// leaves it.
    #[serde(default)]
    pub lighting: Lighting,
    /// The source's licence ("CC BY 4.0", "BSD-3-Clause", ...), as
    /// `sources/LICENSES.md` records it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub licence: Option<String>,
    /// The credit line the licence asks for.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub credit: Option<String>,
    /// The viewer's shelf, when stated; `shelf()` gives the default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shelf: Option<Shelf>,
    /// How the photograph was taken: its colours are those of living
    /// tissue only in vivo.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub capture: Option<Capture>,
    /// How the tissue's surface takes light, when stated; `finish()`
    /// gives the default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub finish: Option<Finish>,
}

/// How a source photograph was taken.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Capture {
    /// Inside a living body (endoscopy, laparoscopy, fundus camera).
    InVivo,
    /// Tissue outside the body (an explanted organ, a phantom).
    ExVivo,
    /// A stained section under a microscope.
    Histology,
    /// Composed from other photographs.
    Composed,
}

impl Capture {
    pub fn name(self) -> &'static str {
        match self {
            Capture::InVivo => "in vivo",
            Capture::ExVivo => "ex vivo",
            Capture::Histology => "histology",
            Capture::Composed => "composed",
        }
    }
}

/// How a tissue's surface takes light (the renderer's and the .glb's
/// material): the tissue's own roughness under a clear coat, the wet film
/// of mucus or serous fluid, of some weight and roughness (glTF's
/// KHR_materials_clearcoat).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Finish {
    pub roughness: f64,
    #[serde(default)]
    pub coat: f64,
    #[serde(default = "default_coat_roughness")]
    pub coat_roughness: f64,
}

fn default_coat_roughness() -> f64 {
    0.15
}

impl Finish {
    /// A living surface: matte tissue under a glistening film.
    pub const WET: Finish = Finish {
        roughness: 0.6,
        coat: 1.0,
        coat_roughness: 0.15,
    };
    /// A dry surface (a stained section, a cut face seen as a picture).
    pub const DRY: Finish = Finish {
        roughness: 0.8,
        coat: 0.0,
        coat_roughness: 0.5,
    };
}

impl Tissue {
    /// The surface finish: as stated, else wet for a surface tissue, dry
    /// for the rest.
    pub fn finish(&self) -> Finish {
        self.finish.unwrap_or(if self.shelf() == Shelf::Surface {
            Finish::WET
        } else {
            Finish::DRY
        })
    }

    /// The credit line, else the licence, for showing beside the tissue.
    pub fn credit_line(&self) -> &str {
        self.credit
            .as_deref()
            .or(self.licence.as_deref())
            .unwrap_or("see the database's sources/LICENSES.md")
    }

    /// The shelf the entry is shown on: as stated, else overlay for an
    /// entry that only makes an overlay, interior for a layered exemplar
    /// without a colour texture, else surface.
    pub fn shelf(&self) -> Shelf {
        self.shelf.unwrap_or(if self.outputs == [Output::Overlay] {
            Shelf::Overlay
        } else if !self.outputs.contains(&Output::Colour) && self.outputs.contains(&Output::Layers)
        {
            Shelf::Interior
        } else {
            Shelf::Surface
        })
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Lighting {
    #[default]
    Keep,
    Flatten,
}

/// Where the viewer shows an entry: a texture for organ surfaces, one for
/// cut surfaces and interiors (histology), or a vessel overlay.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Shelf {
    #[default]
    Surface,
    Interior,
    Overlay,
}

impl Shelf {
    pub const ALL: [Shelf; 3] = [Shelf::Surface, Shelf::Interior, Shelf::Overlay];

    pub fn title(self) -> &'static str {
        match self {
            Shelf::Surface => "Surface",
            Shelf::Interior => "Interior",
            Shelf::Overlay => "Overlay",
        }
    }
}

/// A database: its folder and entries.
#[derive(Clone, Debug)]
pub struct Database {
    pub root: PathBuf,
    pub tissues: Vec<Tissue>,
}

impl Database {
    /// Read and check `root/index.toml`.
    pub fn open(root: &Path) -> Result<Database> {
        let path = root.join("index.toml");
        let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
        let index: IndexFile = toml::from_str(&text).map_err(|e| toml_error(&path, &text, e))?;
        let mut seen = HashSet::new();
        for t in &index.tissue {
            let fail = |msg: String| Error::format(&path, format!("tissue '{}': {msg}", t.id));
            if !seen.insert(t.id.as_str()) {
                return Err(fail("the id is used twice".into()));
            }
            if t.id.is_empty()
                || !t
                    .id
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
            {
                return Err(fail("ids use letters, digits, '-' and '_' only".into()));
            }
            for file in std::iter::once(&t.source).chain(&t.mask) {
                if !root.join(file).is_file() {
                    return Err(fail(format!(
                        "{} does not exist in {}",
                        file.display(),
                        root.display()
                    )));
                }
            }
            let max = crate::synth::fnpts::MAX_OCCURRENCE;
            if let Some(o) = t.synthesis.as_ref().map(|p| p.occurrence)
                && !(0.0..=max).contains(&o)
            {
                return Err(fail(format!(
                    "synthesis.occurrence must be from 0 to {max}, not {o}"
                )));
            }
            let synthesised = t
                .outputs
                .iter()
                .any(|o| matches!(o, Output::Colour | Output::Height));
            if synthesised && t.synthesis.is_none() {
                return Err(fail(
                    "colour and height outputs need a [tissue.synthesis] table".into(),
                ));
            }
            if t.outputs.is_empty() {
                return Err(fail("no outputs".into()));
            }
            let overlay_only = t.outputs == [Output::Overlay];
            let colour = t.outputs.contains(&Output::Colour);
            let shelf = t.shelf();
            if overlay_only != (shelf == Shelf::Overlay) || (shelf == Shelf::Surface && !colour) {
                return Err(fail(format!(
                    "shelf = \"{}\" does not fit outputs [{}]: the overlay shelf holds the entries \
                     that make an overlay alone, the surface shelf those with a colour texture",
                    shelf.title().to_lowercase(),
                    t.outputs
                        .iter()
                        .map(|o| format!("\"{}\"", o.name()))
                        .collect::<Vec<_>>()
                        .join(", ")
                )));
            }
        }
        Ok(Database {
            root: root.to_path_buf(),
            tissues: index.tissue,
        })
    }

    pub fn tissue(&self, id: &str) -> Result<&Tissue> {
        self.tissues.iter().find(|t| t.id == id).ok_or_else(|| {
            Error::invalid(format!(
                "no tissue '{id}' in the database at {} (it has: {})",
                self.root.display(),
                self.tissues
                    .iter()
                    .map(|t| t.id.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
        })
    }

    /// Where `db build` writes an entry's output.
    pub fn output_path(&self, id: &str, output: Output) -> PathBuf {
        self.root.join("build").join(id).join(output.file_name())
    }
}

/// A TOML error as "file:line: message (key ...)".
fn toml_error(path: &Path, text: &str, e: toml::de::Error) -> Error {
    // Counted in bytes: a span need not start on a character boundary.
    let line = e.span().map(|s| {
        let before = &text.as_bytes()[..s.start.min(text.len())];
        before.iter().filter(|&&b| b == b'\n').count() + 1
    });
    let msg = e.message().to_string();
    match line {
        Some(line) => Error::at_line(path, line, msg),
        None => Error::format(path, msg),
    }
}
