"""Per-pixel image quality measures that portico's C++ does not compute itself."""
