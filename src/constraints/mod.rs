//! Constraints projected after the implicit solve and before collision handling: long range
//! attachments (`lra`, Kim, Chentanez & Müller 2012) with their material-space distances
//! (`geodesic`), and strain limiting on the faces' principal stretches (`strain_limit`).
//!
//! A stage module: it reads the mesh and plain parameters, and imports neither `scene` nor
//! `sim`.

pub mod geodesic;
pub mod lra;
pub mod strain_limit;

pub use lra::{Distance, Lra, LraParams};
pub use strain_limit::{StrainLimitReport, StrainLimiter};
