//! `epf.rrd`.
