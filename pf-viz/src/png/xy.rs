//! Plots in the plane with equal axes: paths, points, segments (bearing rays) and error ellipses.
