//! placeholder: filled by the gpu work
