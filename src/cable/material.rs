//! Material presets: section properties of common ropes derived from the
//! nominal diameter.
//!
//! | preset | mass μ | axial EA | bending EI | torsion GJ | sources |
//! |---|---|---|---|---|---|
//! | `steel_wire_rope_6x36_iwrc` | 0.00400·d² kg/m (d in mm) | E_r·A_m, E_r = 100 GPa, A_m = 0.58·πd²/4 | 0.032·E_w·πd⁴/64, E_w = 200 GPa | 0.67·EI | μ: EN 12385-4 table for 6x36WS-IWRC (4.00 kg/100 m/mm²); fill factor 0.58 and rope modulus ~100 GPa: Feyrer, *Wire Ropes* (2015) §3.3; EI between the no-slip and full-slip bounds (Papailiou 1997), chosen so a 20 mm rope has EI ≈ 50 N·m² |
//! | `fibre_rope_polyester` | 0.00078·d² kg/m | 5 GPa · πd²/4 | 0.01·5 GPa·πd⁴/64 | 0.67·EI | polyester density 1380 kg/m³ with fill 0.72 (CI 1304 / ISO 1141 mass tables ≈ 0.30 kg/m at 20 mm); EA/MBL ≈ 25 at mid-range load (Bosman & Hooker, OTC 1999) |
//!
//! The bending stiffness of a stranded rope is not a material constant: it
//! drops between the full-stick value (`E πd⁴/64`) and the full-slip value
//! (sum of the individual wires) as the wires slide. The presets take a fixed
//! intermediate value; give `ei` explicitly where it matters.

/// Section properties of a rope (SI units).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "app", derive(bevy::reflect::Reflect))]
pub struct RopeSection {
    /// Linear density μ, kg/m.
    pub linear_density: f64,
    /// Axial stiffness EA, N.
    pub ea: f64,
    /// Bending stiffness EI about the first transverse axis, N·m².
    pub ei: f64,
    /// Bending stiffness EI about the second transverse axis, N·m².
    pub ei2: f64,
    /// Torsional stiffness GJ, N·m².
    pub gj: f64,
    /// Minimum breaking load, N (0 when unknown).
    pub min_breaking_load: f64,
}

/// Names of the material presets accepted by [`preset`].
pub const PRESET_NAMES: &[&str] = &["steel_wire_rope_6x36_iwrc", "fibre_rope_polyester"];

/// The section of preset `name` for a rope of nominal diameter `diameter`
/// (m), or `None` if the name is unknown.
pub fn preset(name: &str, diameter: f64) -> Option<RopeSection> {
    let d_mm = diameter * 1000.0;
    let area = std::f64::consts::PI * diameter * diameter / 4.0;
    let i_solid = std::f64::consts::PI * diameter.powi(4) / 64.0;
    match name {
        "steel_wire_rope_6x36_iwrc" => {
            let ei = 0.032 * 200e9 * i_solid;
            Some(RopeSection {
                linear_density: 0.00400 * d_mm * d_mm,
                ea: 100e9 * 0.58 * area,
                ei,
                ei2: ei,
                gj: 0.67 * ei,
                // EN 12385-4: F_min = K d² R_r / 1000 kN, K = 0.356, R_r = 1960 MPa.
                min_breaking_load: 0.356 * d_mm * d_mm * 1960.0,
            })
        }
        "fibre_rope_polyester" => {
            let ei = 0.01 * 5e9 * i_solid;
            Some(RopeSection { linear_density: 0.00078 * d_mm * d_mm, ea: 5e9 * area, ei, ei2: ei, gj: 0.67 * ei, min_breaking_load: 5e9 * area / 25.0 })
        }
        _ => None,
    }
}

/// A rope's material and nominal diameter: the typed form of [`preset`],
/// so that the diameter is given once and a name cannot be misspelt.
///
/// ```
/// use bevy_rapier_cable::cable::RopeMaterial;
/// let m = RopeMaterial::steel_6x36_iwrc(0.020);
/// assert_eq!(m.diameter(), 0.020);
/// assert!((m.section().linear_density - 1.6).abs() < 1e-12); // kg/m
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "app", derive(bevy::reflect::Reflect))]
pub enum RopeMaterial {
    /// Steel wire rope 6×36 IWRC (preset `steel_wire_rope_6x36_iwrc`).
    SteelWireRope6x36Iwrc {
        /// Nominal diameter, m.
        diameter: f64,
    },
    /// Polyester fibre rope (preset `fibre_rope_polyester`).
    FibreRopePolyester {
        /// Nominal diameter, m.
        diameter: f64,
    },
    /// A section given property by property.
    Custom {
        /// The section (mass, stiffnesses, breaking load).
        section: RopeSection,
        /// Diameter, m (drawing, contact, drag).
        diameter: f64,
    },
}

impl Default for RopeMaterial {
    /// A 20 mm steel wire rope 6×36 IWRC (1.6 kg/m, EA 1.8·10⁷ N).
    fn default() -> Self {
        RopeMaterial::steel_6x36_iwrc(0.020)
    }
}

impl RopeMaterial {
    /// Steel wire rope 6×36 IWRC of nominal `diameter`, m.
    pub fn steel_6x36_iwrc(diameter: f64) -> Self {
        RopeMaterial::SteelWireRope6x36Iwrc { diameter }
    }

    /// Polyester fibre rope of nominal `diameter`, m.
    pub fn polyester(diameter: f64) -> Self {
        RopeMaterial::FibreRopePolyester { diameter }
    }

    /// A section given property by property, drawn with `diameter`, m.
    pub fn custom(section: RopeSection, diameter: f64) -> Self {
        RopeMaterial::Custom { section, diameter }
    }

    /// The preset's name ([`PRESET_NAMES`]), or `"custom"`.
    pub fn name(&self) -> &'static str {
        match self {
            RopeMaterial::SteelWireRope6x36Iwrc { .. } => "steel_wire_rope_6x36_iwrc",
            RopeMaterial::FibreRopePolyester { .. } => "fibre_rope_polyester",
            RopeMaterial::Custom { .. } => "custom",
        }
    }

    /// Nominal diameter, m.
    pub fn diameter(&self) -> f64 {
        match *self {
            RopeMaterial::SteelWireRope6x36Iwrc { diameter } | RopeMaterial::FibreRopePolyester { diameter } | RopeMaterial::Custom { diameter, .. } => {
                diameter
            }
        }
    }

    /// The section properties (SI units).
    pub fn section(&self) -> RopeSection {
        match *self {
            RopeMaterial::Custom { section, .. } => section,
            _ => preset(self.name(), self.diameter()).expect("every named variant is a preset"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steel_20mm_matches_catalogue_values() {
        let s = preset("steel_wire_rope_6x36_iwrc", 0.020).unwrap();
        assert!((s.linear_density - 1.6).abs() < 1e-12);
        assert!((s.ea - 1.822e7).abs() / 1.822e7 < 1e-3);
        assert!((s.ei - 50.27).abs() < 0.1);
        assert!((s.min_breaking_load - 279_104.0).abs() < 1.0);
        assert!(preset("unobtainium", 0.02).is_none());
    }

    #[test]
    fn typed_materials_are_the_presets() {
        for (m, name) in [(RopeMaterial::steel_6x36_iwrc(0.024), "steel_wire_rope_6x36_iwrc"), (RopeMaterial::polyester(0.03), "fibre_rope_polyester")] {
            assert_eq!(m.name(), name);
            assert_eq!(Some(m.section()), preset(name, m.diameter()));
        }
        let s = preset("steel_wire_rope_6x36_iwrc", 0.01).unwrap();
        assert_eq!(RopeMaterial::custom(s, 0.011).section(), s);
        assert_eq!(RopeMaterial::custom(s, 0.011).diameter(), 0.011);
        assert_eq!(PRESET_NAMES.len(), 2, "a new preset needs a RopeMaterial variant");
    }
}
