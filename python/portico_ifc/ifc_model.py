"""Reads an IFC model with IfcOpenShell into plain triangle meshes.

Axes: IFC is Z-up, portico is Y-up; a point (x, y, z) of the model becomes
(x, z, -y), a rotation, so triangle windings keep their front. Lengths come
out of IfcOpenShell in metres whatever the file's length unit (it applies the
file's unit scale; the scale is reported).
"""

import multiprocessing
from dataclasses import dataclass, field

import numpy as np
import ifcopenshell
import ifcopenshell.geom
import ifcopenshell.util.element
import ifcopenshell.util.unit

# Elements whose solids close a room: a cell face inside one of them is sealed.
SEALING_TYPES = ("IfcWall", "IfcSlab", "IfcRoof", "IfcCovering", "IfcColumn", "IfcBeam", "IfcPlate",
                 "IfcCurtainWall", "IfcFooting", "IfcChimney")
# Doors and windows are dropped: their openings (cut into the walls by
# IfcOpenShell) stay open and become portals. Openings, spaces, the site and
# annotations are not surfaces.
SKIPPED_TYPES = ("IfcDoor", "IfcWindow", "IfcOpeningElement", "IfcSpace", "IfcSite", "IfcAnnotation",
                 "IfcGrid", "IfcVirtualElement")
DEFAULT_ALBEDO = (0.6, 0.6, 0.6)


@dataclass
class Mesh:
    vertices: np.ndarray          # (n, 3) float64, portico axes
    triangles: np.ndarray         # (m, 3) int64

    # Computed once: the sealing tests ask for them thousands of times.
    _corners: np.ndarray = field(default=None, init=False, repr=False, compare=False)
    _triangle_bounds: tuple = field(default=None, init=False, repr=False, compare=False)

    def bounds(self):
        return self.vertices.min(axis=0), self.vertices.max(axis=0)

    def corners(self):
        """(m, 3, 3): the corners of every triangle (read-only)."""
        if self._corners is None:
            self._corners = self.vertices[self.triangles]
            self._corners.flags.writeable = False
        return self._corners

    def triangle_bounds(self):
        """((m, 3), (m, 3)): every triangle's box."""
        if self._triangle_bounds is None:
            c = self.corners()
            self._triangle_bounds = (c.min(axis=1), c.max(axis=1))
        return self._triangle_bounds


@dataclass
class Element:
    ifc_type: str
    name: str
    guid: str
    mesh: Mesh
    material_of_triangle: np.ndarray = None   # (m,) indices into IfcModel.materials
    sealing: bool = False


@dataclass
class Space:
    name: str
    guid: str
    mesh: Mesh


@dataclass
class Opening:
    """A door's or window's hole: the opening element it fills, else its own box."""
    kind: str                     # "door" or "window"
    name: str
    lo: np.ndarray
    hi: np.ndarray
    host: tuple = ()              # GlobalIds of the wall, slab or roof it is cut from, and of its parts
    across: int = None            # the axis through the hole: across its host


@dataclass
class Fixture:
    name: str
    lo: np.ndarray
    hi: np.ndarray
    watts: float = None


@dataclass
class IfcModel:
    name: str
    schema: str
    unit_scale: float
    elements: list = field(default_factory=list)
    spaces: list = field(default_factory=list)
    openings: list = field(default_factory=list)
    fixtures: list = field(default_factory=list)
    materials: list = field(default_factory=list)     # [(name, (r, g, b))]


def to_portico_axes(flat_vertices):
    v = np.asarray(flat_vertices, dtype=np.float64).reshape(-1, 3)
    return np.stack([v[:, 0], v[:, 2], -v[:, 1]], axis=1)


def _settings():
    s = ifcopenshell.geom.settings()
    s.set("use-world-coords", True)
    return s


def _iterate_shapes(model, products):
    """Yields (product, geometry) for every product IfcOpenShell can tessellate."""
    if not products:
        return
    iterator = ifcopenshell.geom.iterator(_settings(), model, max(1, multiprocessing.cpu_count()), include=products)
    if not iterator.initialize():
        return
    while True:
        shape = iterator.get()
        yield model.by_id(shape.id), shape.geometry
        if not iterator.next():
            break


def _is_light_fixture(product):
    if product.is_a("IfcLightFixture"):
        return True
    if product.is_a("IfcFlowTerminal"):     # IFC2x3: typed by an IfcLightFixtureType
        element_type = ifcopenshell.util.element.get_type(product)
        return element_type is not None and element_type.is_a("IfcLightFixtureType")
    return False


def _fixture_watts(product):
    for pset in ifcopenshell.util.element.get_psets(product).values():
        for key in ("Wattage", "Power", "TotalWattage"):
            value = pset.get(key)
            if isinstance(value, (int, float)) and value > 0:
                return float(value)
    return None


def _opening_of(product):
    for rel in getattr(product, "FillsVoids", None) or []:
        return rel.RelatingOpeningElement
    return None


def _host_of(opening):
    """GlobalIds of the wall, slab or roof an opening element is cut from and
    of its parts: a roof is often an aggregate whose slabs carry the shape."""
    for rel in getattr(opening, "VoidsElements", None) or []:
        host = rel.RelatingBuildingElement
        return (host.GlobalId,) + tuple(p.GlobalId for p in ifcopenshell.util.element.get_decomposition(host))
    return ()


def _through_host(opening, host_bounds):
    """Sets the axis through the hole and its depth along that axis from the
    host's box: the host is thinnest across the hole, while an opening
    element may be extruded well beyond it (a skylight's runs metres above
    the roof, so that its own box is thinnest sideways). Without a host, the
    hole's own box decides."""
    if host_bounds is None:
        opening.across = int(np.argmin(opening.hi - opening.lo))
        return
    host_lo, host_hi = host_bounds
    axis = int(np.argmin(host_hi - host_lo))
    lo, hi = max(opening.lo[axis], host_lo[axis]), min(opening.hi[axis], host_hi[axis])
    if lo < hi:
        opening.lo[axis], opening.hi[axis] = lo, hi
    opening.across = axis


class _MaterialTable:
    def __init__(self):
        self.entries, self.index = [], {}

    def add(self, name, rgb):
        rgb = tuple(round(min(1.0, max(0.0, float(c))), 4) for c in rgb)
        key = (name, rgb)
        if key not in self.index:
            self.index[key] = len(self.entries)
            self.entries.append(key)
        return self.index[key]


def _style_albedo(material):
    diffuse = material.diffuse
    rgb = (diffuse.r(), diffuse.g(), diffuse.b()) if hasattr(diffuse, "r") else tuple(diffuse)[:3]
    return rgb if all(c >= 0 for c in rgb) else DEFAULT_ALBEDO


def read_ifc(path):
    model = ifcopenshell.open(path)
    project = model.by_type("IfcProject")
    result = IfcModel(name=(project[0].Name if project and project[0].Name else ""), schema=model.schema,
                      unit_scale=float(ifcopenshell.util.unit.calculate_unit_scale(model)))
    materials = _MaterialTable()
    materials.add("default", DEFAULT_ALBEDO)

    products = [p for p in model.by_type("IfcProduct") if p.Representation is not None]
    surfaces = [p for p in products if not any(p.is_a(t) for t in SKIPPED_TYPES)]
    fixtures = {p.id() for p in surfaces if _is_light_fixture(p)}
    holes = {}
    for p in list(model.by_type("IfcDoor")) + list(model.by_type("IfcWindow")):
        opening = _opening_of(p)
        host = _host_of(opening) if opening else ()
        holes[(opening or p).id()] = (p, "door" if p.is_a("IfcDoor") else "window", host)
    wanted = surfaces + list(model.by_type("IfcSpace")) + [model.by_id(i) for i in holes]
    wanted = [p for p in {p.id(): p for p in wanted if p.Representation is not None}.values()]

    for product, geometry in _iterate_shapes(model, wanted):
        vertices = to_portico_axes(geometry.verts)
        triangles = np.asarray(geometry.faces, dtype=np.int64).reshape(-1, 3)
        if len(triangles) == 0:
            continue
        mesh = Mesh(vertices, triangles)
        name = product.Name or product.GlobalId
        if product.id() in holes:
            filled, kind, host = holes[product.id()]
            lo, hi = mesh.bounds()
            result.openings.append(Opening(kind, filled.Name or filled.GlobalId, lo, hi, host))
        if product.is_a("IfcSpace"):
            label = " ".join(x for x in (product.Name, product.LongName) if x) or product.GlobalId
            result.spaces.append(Space(label, product.GlobalId, mesh))
            continue
        if product.id() in holes:
            continue
        if product.id() in fixtures:
            lo, hi = mesh.bounds()
            result.fixtures.append(Fixture(name, lo, hi, _fixture_watts(product)))
        ids = [materials.add(m.name, _style_albedo(m)) for m in geometry.materials]
        per_triangle = np.asarray(geometry.material_ids, dtype=np.int64)
        if ids and len(per_triangle) == len(triangles):
            lookup = np.asarray(ids, dtype=np.int64)
            of_triangle = np.where(per_triangle >= 0, lookup[np.clip(per_triangle, 0, len(ids) - 1)], 0)
        else:
            of_triangle = np.zeros(len(triangles), dtype=np.int64)
        result.elements.append(Element(product.is_a(), name, product.GlobalId, mesh, of_triangle,
                                       sealing=any(product.is_a(t) for t in SEALING_TYPES)))
    element_bounds = {e.guid: e.mesh.bounds() for e in result.elements}
    for o in result.openings:
        boxes = [element_bounds[g] for g in o.host if g in element_bounds]
        _through_host(o, (np.min([b[0] for b in boxes], axis=0), np.max([b[1] for b in boxes], axis=0))
                      if boxes else None)
    # Materials are met in the order the threads finish shapes: number them
    # by name and colour instead ("default" stays first).
    order = [0] + sorted(range(1, len(materials.entries)), key=lambda i: materials.entries[i])
    renumber = np.empty(len(order), dtype=np.int64)
    renumber[order] = np.arange(len(order))
    result.materials = [materials.entries[i] for i in order]
    for e in result.elements:
        e.material_of_triangle = renumber[e.material_of_triangle]
    # Same model, same order: sort by GlobalId so that the output never depends on threads.
    result.elements.sort(key=lambda e: (e.guid, e.ifc_type))
    result.spaces.sort(key=lambda s: (s.name, s.guid))
    result.openings.sort(key=lambda o: (o.kind, o.name, tuple(o.lo)))
    result.fixtures.sort(key=lambda f: (f.name, tuple(f.lo)))
    return result
