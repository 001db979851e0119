//! A model as an exported library carries it (`twv-bundle/1`): the IR text with the parameter
//! values it runs with. `twv export` writes one; the export runtime (`twv-export`) reads it back
//! from an FMU's `resources/` folder or from the end of a CasADi library, so both sides share
//! this one format and its checks.

use serde::{Deserialize, Serialize};

use crate::params::check_values;
use crate::types::Ir;
use crate::validate::parse_ir;

/// The only bundle format this crate reads.
pub const BUNDLE_FORMAT: &str = "twv-bundle/1";

/// What ends a library file that carries a bundle: the 8 bytes of [`TRAILER_MAGIC`], then the
/// bundle's length as 8 little-endian bytes, after the bundle's own bytes.
pub const TRAILER_MAGIC: &[u8; 8] = b"TWVBNDL1";

/// The bundle's file name in an FMU's `resources/` folder.
pub const FMU_RESOURCE: &str = "bundle.json";

/// The largest bundle a reader accepts (the Whipple bicycle's IR is 1.4 MB).
pub const MAX_BUNDLE_BYTES: u64 = 256 << 20;

/// An IR with the parameter values it runs with.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bundle {
    /// [`BUNDLE_FORMAT`].
    pub format: String,
    /// The model IR, as the text of its file (`twv-ir/1`).
    pub ir: String,
    /// Parameter values in the IR's order (validated as a parameter file's).
    pub params: Vec<f64>,
    /// Where the values came from (a file, or the defaults), for people reading the bundle.
    pub params_origin: String,
    /// The largest RK4 step of a co-simulation step [s] (an FMU's `fmi2DoStep`).
    pub rk4_step: f64,
    /// Whether the parameters are variables a user may set (an FMU's tunable parameters, a
    /// CasADi function's input `p`), or fixed at the bundle's values.
    pub tunable: bool,
}

/// A variable of an exported FMU, by what it is: its value reference is its place in the order
/// states, their derivatives, inputs, parameters (the order of `modelDescription.xml`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Variable {
    /// State `i`.
    State(usize),
    /// The derivative of state `i`.
    Derivative(usize),
    /// Input `j`.
    Input(usize),
    /// Parameter `k` (tunable bundles only).
    Param(usize),
}

/// The value references of a model with `nx` states, `nu` inputs and `np` parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ValueReferences {
    pub nx: usize,
    pub nu: usize,
    /// Parameters that are variables (0 when they are fixed).
    pub np: usize,
}

impl ValueReferences {
    /// The value reference of `v` (also its 0-based index in `ModelVariables`).
    pub fn of(&self, v: Variable) -> u32 {
        let (nx, nu) = (self.nx, self.nu);
        (match v {
            Variable::State(i) => i,
            Variable::Derivative(i) => nx + i,
            Variable::Input(j) => 2 * nx + j,
            Variable::Param(k) => 2 * nx + nu + k,
        }) as u32
    }

    /// The variable of value reference `vr`, if there is one.
    pub fn variable(&self, vr: u32) -> Option<Variable> {
        let (nx, nu, np) = (self.nx, self.nu, self.np);
        let r = vr as usize;
        Some(if r < nx {
            Variable::State(r)
        } else if r < 2 * nx {
            Variable::Derivative(r - nx)
        } else if r < 2 * nx + nu {
            Variable::Input(r - 2 * nx)
        } else if r < 2 * nx + nu + np {
            Variable::Param(r - 2 * nx - nu)
        } else {
            return None;
        })
    }

    /// Number of variables.
    pub fn len(&self) -> usize {
        2 * self.nx + self.nu + self.np
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A bundle that cannot be used, said in one line.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct BundleError(pub String);

impl Bundle {
    /// A bundle of `ir_text` with `params` (the IR and the values are checked here, so that an
    /// exported library never carries a model its runtime would refuse).
    pub fn new(
        ir_text: &str,
        params: Vec<f64>,
        params_origin: &str,
        rk4_step: f64,
        tunable: bool,
    ) -> Result<Self, BundleError> {
        let bundle = Bundle {
            format: BUNDLE_FORMAT.to_string(),
            ir: ir_text.to_string(),
            params,
            params_origin: params_origin.to_string(),
            rk4_step,
            tunable,
        };
        bundle.model()?;
        Ok(bundle)
    }

    /// The bundle as JSON text (deterministic: the same model and values, the same bytes).
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }

    /// A bundle from its JSON text, checked.
    pub fn parse(text: &[u8], origin: &str) -> Result<Self, BundleError> {
        if text.len() as u64 > MAX_BUNDLE_BYTES {
            return Err(BundleError(format!(
                "{origin}: {} bytes, more than a bundle may have ({MAX_BUNDLE_BYTES})",
                text.len()
            )));
        }
        let bundle: Bundle = serde_json::from_slice(text)
            .map_err(|e| BundleError(format!("{origin}: not a twv bundle: {e}")))?;
        if bundle.format != BUNDLE_FORMAT {
            return Err(BundleError(format!(
                "{origin}: format is {:?}, expected {BUNDLE_FORMAT:?}",
                bundle.format
            )));
        }
        bundle.model()?;
        Ok(bundle)
    }

    /// The validated IR and values.
    pub fn model(&self) -> Result<(Ir, Vec<f64>), BundleError> {
        if !(self.rk4_step.is_finite() && self.rk4_step > 0.0) {
            return Err(BundleError(format!(
                "rk4_step {} is not a positive step",
                self.rk4_step
            )));
        }
        let ir = parse_ir(&self.ir, "bundle IR").map_err(|e| BundleError(e.to_string()))?;
        if self.params.len() != ir.np() {
            return Err(BundleError(format!(
                "{} parameter values for a model with {}",
                self.params.len(),
                ir.np()
            )));
        }
        check_values(&self.params, &self.params_origin, ir.params())
            .map_err(|e| BundleError(e.to_string()))?;
        Ok((ir, self.params.clone()))
    }

    /// `library` with this bundle appended as its trailer (what a loader ignores: the bytes
    /// after an ELF file's sections are not mapped by any segment).
    pub fn append_to(&self, library: &[u8]) -> Vec<u8> {
        let json = self.to_json();
        let mut out = Vec::with_capacity(library.len() + json.len() + 16);
        out.extend_from_slice(library);
        out.extend_from_slice(json.as_bytes());
        out.extend_from_slice(TRAILER_MAGIC);
        out.extend_from_slice(&(json.len() as u64).to_le_bytes());
        out
    }

    /// The bundle at the end of `file` (a library written by [`append_to`](Self::append_to)),
    /// reading only its last bytes.
    pub fn from_trailer(file: &std::path::Path) -> Result<Self, BundleError> {
        use std::io::{Read, Seek, SeekFrom};
        let origin = file.display().to_string();
        let io = |e: std::io::Error| BundleError(format!("{origin}: {e}"));
        let mut f = std::fs::File::open(file).map_err(io)?;
        let size = f.metadata().map_err(io)?.len();
        let mut tail = [0u8; 16];
        if size < 16 {
            return Err(BundleError(format!("{origin}: carries no twv bundle")));
        }
        f.seek(SeekFrom::Start(size - 16)).map_err(io)?;
        f.read_exact(&mut tail).map_err(io)?;
        if &tail[..8] != TRAILER_MAGIC {
            return Err(BundleError(format!(
                "{origin}: carries no twv bundle (written by `twv export --casadi`?)"
            )));
        }
        let len = u64::from_le_bytes(tail[8..].try_into().unwrap_or_default());
        if len > MAX_BUNDLE_BYTES || len > size - 16 {
            return Err(BundleError(format!(
                "{origin}: its bundle's length {len} does not fit the file"
            )));
        }
        f.seek(SeekFrom::Start(size - 16 - len)).map_err(io)?;
        let mut text = vec![0u8; len as usize];
        f.read_exact(&mut text).map_err(io)?;
        Bundle::parse(&text, &origin)
    }
}

impl Bundle {
    /// The FMI GUID of an export of this bundle: a SHA-256 of its JSON in the 8-4-4-4-12 form,
    /// so the same model and values give the same GUID, and `modelDescription.xml` and the
    /// resources of two different exports are told apart at instantiation.
    pub fn guid(&self) -> String {
        let hash = crate::hash::sha256_hex(&self.to_json());
        let hex = hash.trim_start_matches("sha256:");
        format!(
            "{{{}-{}-{}-{}-{}}}",
            &hex[0..8],
            &hex[8..12],
            &hex[12..16],
            &hex[16..20],
            &hex[20..32]
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LORENZ: &str = include_str!("../../../generated/ir/lorenz.json");

    fn lorenz() -> Bundle {
        let ir = parse_ir(LORENZ, "lorenz.json").unwrap();
        Bundle::new(LORENZ, ir.defaults(), "defaults", 1e-3, false).unwrap()
    }

    /// A bundle survives its JSON and a trailer; the GUID is its hash and changes with a value.
    #[test]
    fn a_bundle_round_trips_and_its_guid_follows_its_values() {
        let b = lorenz();
        assert_eq!(Bundle::parse(b.to_json().as_bytes(), "b").unwrap(), b);
        let dir = std::env::temp_dir().join(format!("twv-bundle-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let lib = dir.join("lib.so");
        std::fs::write(&lib, b.append_to(b"\x7fELF not really a library")).unwrap();
        assert_eq!(Bundle::from_trailer(&lib).unwrap(), b);
        let mut other = b.clone();
        other.params[0] *= 2.0;
        assert_ne!(other.guid(), b.guid());
        assert_eq!(b.guid().len(), 38);
        // A file without a trailer, a truncated one, a lying length: named, no panic.
        std::fs::write(&lib, b"plain").unwrap();
        assert!(Bundle::from_trailer(&lib)
            .unwrap_err()
            .0
            .contains("no twv bundle"));
        let mut bytes = b.append_to(b"x");
        bytes.drain(1..20);
        std::fs::write(&lib, &bytes).unwrap();
        assert!(Bundle::from_trailer(&lib).is_err());
        let mut bytes = b"x".to_vec();
        bytes.extend_from_slice(TRAILER_MAGIC);
        bytes.extend_from_slice(&u64::MAX.to_le_bytes());
        std::fs::write(&lib, &bytes).unwrap();
        assert!(Bundle::from_trailer(&lib)
            .unwrap_err()
            .0
            .contains("does not fit"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// What the runtime would refuse is refused when the bundle is made.
    #[test]
    fn a_bundle_of_bad_values_is_refused() {
        let ir = parse_ir(LORENZ, "lorenz.json").unwrap();
        assert!(Bundle::new(LORENZ, vec![1.0], "x", 1e-3, false).is_err());
        assert!(Bundle::new(LORENZ, ir.defaults(), "x", 0.0, false).is_err());
        let mut nan = ir.defaults();
        nan[0] = f64::NAN;
        assert!(Bundle::new(LORENZ, nan, "x", 1e-3, false).is_err());
        assert!(Bundle::parse(b"{}", "b").is_err());
    }

    /// Value references run states, derivatives, inputs, parameters, and back.
    #[test]
    fn value_references_are_a_bijection() {
        let refs = ValueReferences {
            nx: 3,
            nu: 2,
            np: 4,
        };
        for vr in 0..refs.len() as u32 {
            let v = refs.variable(vr).unwrap();
            assert_eq!(refs.of(v), vr);
        }
        assert_eq!(refs.variable(refs.len() as u32), None);
        assert_eq!(refs.variable(3), Some(Variable::Derivative(0)));
        assert_eq!(refs.variable(6), Some(Variable::Input(0)));
    }
}
