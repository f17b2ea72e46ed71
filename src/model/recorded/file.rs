//! model.json
