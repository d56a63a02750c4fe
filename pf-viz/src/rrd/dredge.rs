//! `dredge.rrd`.
