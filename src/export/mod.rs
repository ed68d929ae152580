//! placeholder: filled by the export work
