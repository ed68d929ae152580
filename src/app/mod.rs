//! placeholder: filled by the app work
