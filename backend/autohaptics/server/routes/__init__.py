"""HTTP routes, one module per area of docs/API.md; each exposes ``router``."""
