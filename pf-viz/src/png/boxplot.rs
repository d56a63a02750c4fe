//! Box plots: one box per group (quartiles, 1.5 IQR whiskers, outliers), with labelled horizontal reference lines.
