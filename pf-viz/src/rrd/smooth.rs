//! `smooth.rrd`.
