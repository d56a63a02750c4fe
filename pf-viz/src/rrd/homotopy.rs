//! `homotopy.rrd`.
