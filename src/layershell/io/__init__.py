"""Model files (TOML schema, builder), outputs."""
