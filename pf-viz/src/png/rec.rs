//! REC curves (regression error characteristic): accuracy against error tolerance, one curve per method.
