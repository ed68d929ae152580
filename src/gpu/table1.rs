//! The paper's Table 1 on synthetic systems (placeholder until the benchmark lands).
