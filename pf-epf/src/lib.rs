//! pf-epf
pub mod assignment;
pub mod association;
pub mod dynamics;
pub mod energy;
pub mod error;
pub mod geometry;
pub mod model;
