//! Histograms of samples, with mean, standard deviation and max |·| annotated.
