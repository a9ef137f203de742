//! Beam lattice extension (1.2): beams between the vertices of a mesh, with a
//! radius at each end and a cap at each end, balls at nodes, an optional
//! clipping mesh and a representation mesh for viewers.
//!
//! A lattice-only object is a mesh with the lattice's nodes as vertices and
//! no triangles; the extension is then required (the writer marks it).

/// How a beam end is closed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Cap {
    /// A ball of the end radius (the default).
    #[default]
    Sphere,
    /// Half a ball, on the outside of the beam end.
    Hemisphere,
    /// Flat.
    Butt,
}

impl Cap {
    /// The attribute value.
    pub fn name(self) -> &'static str {
        match self {
            Cap::Sphere => "sphere",
            Cap::Hemisphere => "hemisphere",
            Cap::Butt => "butt",
        }
    }

    /// Parses an attribute value.
    pub fn from_name(s: &str) -> Option<Cap> {
        [Cap::Sphere, Cap::Hemisphere, Cap::Butt]
            .into_iter()
            .find(|c| c.name() == s)
    }
}

/// Which vertices get balls.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BallMode {
    /// No balls (the default).
    #[default]
    None,
    /// Balls only where a `<ball>` is given.
    Mixed,
    /// A ball at every beam end (`ball_radius` unless a `<ball>` says otherwise).
    All,
}

impl BallMode {
    /// The attribute value.
    pub fn name(self) -> &'static str {
        match self {
            BallMode::None => "none",
            BallMode::Mixed => "mixed",
            BallMode::All => "all",
        }
    }

    /// Parses an attribute value.
    pub fn from_name(s: &str) -> Option<BallMode> {
        [BallMode::None, BallMode::Mixed, BallMode::All]
            .into_iter()
            .find(|c| c.name() == s)
    }
}

/// How the lattice is clipped by the clipping mesh.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ClipMode {
    /// Not clipped.
    #[default]
    None,
    /// Keep what is inside the clipping mesh.
    Inside,
    /// Keep what is outside the clipping mesh.
    Outside,
}

impl ClipMode {
    /// The attribute value.
    pub fn name(self) -> &'static str {
        match self {
            ClipMode::None => "none",
            ClipMode::Inside => "inside",
            ClipMode::Outside => "outside",
        }
    }

    /// Parses an attribute value.
    pub fn from_name(s: &str) -> Option<ClipMode> {
        [ClipMode::None, ClipMode::Inside, ClipMode::Outside]
            .into_iter()
            .find(|c| c.name() == s)
    }
}

/// One beam.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Beam {
    /// First vertex (index into the mesh's vertices).
    pub v1: u32,
    /// Second vertex.
    pub v2: u32,
    /// Radius at the first vertex.
    pub r1: f64,
    /// Radius at the second vertex.
    pub r2: f64,
    /// Cap at the first vertex (`None`: the lattice default).
    pub cap1: Option<Cap>,
    /// Cap at the second vertex.
    pub cap2: Option<Cap>,
}

/// A ball at a vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ball {
    /// Vertex index (must be the end of some beam).
    pub vindex: u32,
    /// Radius (`None`: the lattice's ball radius).
    pub r: Option<f64>,
}

/// A named group of beams and balls.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BeamSet {
    /// Human-readable name.
    pub name: Option<String>,
    /// Identifier (unique within the lattice).
    pub identifier: Option<String>,
    /// Beam indices.
    pub beams: Vec<u32>,
    /// Ball indices.
    pub balls: Vec<u32>,
}

/// A `<b:beamlattice>` on a mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct BeamLattice {
    /// Default radius (the writer omits `r1`/`r2` equal to it).
    pub radius: f64,
    /// Beams shorter than this are ignored by consumers (positive).
    pub min_length: f64,
    /// Default cap.
    pub cap: Cap,
    /// The beams.
    pub beams: Vec<Beam>,
    /// Ball mode.
    pub ball_mode: BallMode,
    /// Default ball radius (needed unless `ball_mode` is `None`).
    pub ball_radius: Option<f64>,
    /// Balls.
    pub balls: Vec<Ball>,
    /// Beam sets.
    pub beam_sets: Vec<BeamSet>,
    /// Clipping mode and the object (a mesh defined earlier) it clips by.
    pub clipping: Option<(ClipMode, u32)>,
    /// Object (a mesh defined earlier) that viewers may show instead.
    pub representation: Option<u32>,
}

impl BeamLattice {
    /// An empty lattice with default radius `radius`, sphere caps, no
    /// balls, clipping or representation.
    pub fn new(radius: f64, min_length: f64) -> BeamLattice {
        BeamLattice {
            radius,
            min_length,
            cap: Cap::Sphere,
            beams: Vec::new(),
            ball_mode: BallMode::None,
            ball_radius: None,
            balls: Vec::new(),
            beam_sets: Vec::new(),
            clipping: None,
            representation: None,
        }
    }

    /// Adds a beam with end radii and the default caps.
    pub fn push(&mut self, v1: u32, v2: u32, r1: f64, r2: f64) {
        self.beams.push(Beam {
            v1,
            v2,
            r1,
            r2,
            cap1: None,
            cap2: None,
        });
    }
}
