"""IFC building models -> portico's building.json (docs/importing-buildings.md)."""
