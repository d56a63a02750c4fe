//! `mpf.rrd`.
