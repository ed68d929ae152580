//! placeholder: filled by the render work
