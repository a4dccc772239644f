"""Reads an IFC model with IfcOpenShell into plain triangle meshes.

Axes: IFC is Z-up, portico is Y-up; a point (x, y, z) of the model becomes
(x, z, -y), a rotation, so triangle windings keep their front. Lengths come
out of IfcOpenShell in metres whatever the file's length unit (it applies the
file's unit scale; the scale is reported).
"""

import multiprocessing
import re
from dataclasses import dataclass, field

import numpy as np
import ifcopenshell
import ifcopenshell.geom
import ifcopenshell.util.element
import ifcopenshell.util.unit

# Elements whose solids close a room: a cell face inside one of them is sealed.
SEALING_TYPES = ("IfcWall", "IfcSlab", "IfcRoof", "IfcCovering", "IfcColumn", "IfcBeam", "IfcPlate",
                 "IfcCurtainWall", "IfcFooting", "IfcChimney")
# Doors are dropped: their openings (cut into the walls by IfcOpenShell)
# stay open and become portals. Windows are read on their own (their glass
# becomes thin panes, their frames surfaces), or dropped with glazing off.
# Openings, spaces, the site and annotations are not surfaces.
SKIPPED_TYPES = ("IfcDoor", "IfcWindow", "IfcOpeningElement", "IfcSpace", "IfcSite", "IfcAnnotation",
                 "IfcGrid", "IfcVirtualElement")
DEFAULT_ALBEDO = (0.6, 0.6, 0.6)
# A style named as glass but not transparent (Transparency 0 or absent)
# still is glass: this transparency (clear float glass passes about 90 %).
NAMED_GLASS_TRANSPARENCY = 0.9
GLASS_NAME = re.compile(r"glas|glaz|vitr", re.IGNORECASE)


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
    filler: str = ""              # GlobalId of the door or window


@dataclass
class Glazing:
    """The transparent part of a window: its glass triangles, as modelled
    (often a thin solid per pane), and the glass's transmittance."""
    name: str
    guid: str
    glass: Mesh
    transmittance: tuple
    curtain: bool = False         # a plate of a curtain wall (else a window's glass)


@dataclass
class Site:
    latitude: float               # decimal degrees, north positive
    longitude: float              # decimal degrees, east positive
    true_north: tuple             # (x, y): geographic north in the model's plan (IFC axes)


@dataclass
class Fixture:
    name: str
    lo: np.ndarray
    hi: np.ndarray
    watts: float = None
    lumens: float = None          # luminous flux, lm
    kelvin: float = None          # colour temperature, K


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
    glazings: list = field(default_factory=list)
    unfilled_openings: list = field(default_factory=list)  # Openings (kind "unfilled"): voids no door or window fills
    unglazed_windows: list = field(default_factory=list)   # names of windows without a transparent part
    site: Site = None


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


def _fixture_property(product, keys, low=0.0, high=float("inf")):
    """The first of `keys` in the fixture's property sets (its type's
    included) that is a number in (low, high]."""
    for pset in ifcopenshell.util.element.get_psets(product).values():
        for key in keys:
            value = pset.get(key)
            if isinstance(value, (int, float)) and low < value <= high:
                return float(value)
    return None


def _fixture_watts(product):
    return _fixture_property(product, ("Wattage", "Power", "TotalWattage"))


def _fixture_lumens(product):
    return _fixture_property(product, ("LuminousFlux", "TotalLuminousFlux"))


def _fixture_kelvin(product):
    # The importer accepts 1667-25000 K (docs/photometric-lights.md).
    return _fixture_property(product, ("ColourTemperature", "ColorTemperature"), 1667.0, 25000.0)


def _in_curtain_wall(product):
    """Whether the product is a part of an IfcCurtainWall (its plates are the glazing)."""
    for rel in getattr(product, "Decomposes", None) or []:
        if rel.RelatingObject.is_a("IfcCurtainWall"):
            return True
    return False


def _curtain_transmittance(model, geometry):
    """A curtain wall's plate is glass: its style's transmittance where the
    style is glass, else clear glass's (NAMED_GLASS_TRANSPARENCY)."""
    for material in geometry.materials:
        transmittance = _glass_transmittance(model, material)
        if transmittance is not None:
            return transmittance
    return (NAMED_GLASS_TRANSPARENCY,) * 3


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


def _compound_degrees(angle):
    """IfcCompoundPlaneAngleMeasure (degrees, minutes, seconds[, millionths
    of a second], all of one sign) in decimal degrees."""
    parts = list(angle) + [0] * (4 - len(angle))
    return parts[0] + parts[1] / 60 + parts[2] / 3600 + parts[3] / 3.6e9


def _true_north(model):
    """The Model context's TrueNorth in the plan of the model (IFC x, y),
    turned by its world coordinate system; absent: +y."""
    for context in model.by_type("IfcGeometricRepresentationContext"):
        if context.is_a("IfcGeometricRepresentationSubContext") or context.ContextType != "Model":
            continue
        north = getattr(context, "TrueNorth", None)
        x, y = (north.DirectionRatios[0], north.DirectionRatios[1]) if north else (0.0, 1.0)
        world = context.WorldCoordinateSystem
        ref = getattr(world, "RefDirection", None) if world is not None else None
        if ref is not None:     # the context's x axis in world coordinates: turn by its angle
            c, s = ref.DirectionRatios[0], ref.DirectionRatios[1]
            length = np.hypot(c, s)
            c, s = c / length, s / length
            x, y = c * x - s * y, s * x + c * y
        return (float(x), float(y))
    return (0.0, 1.0)


def _site(model):
    for site in model.by_type("IfcSite"):
        if site.RefLatitude and site.RefLongitude:
            return Site(round(_compound_degrees(site.RefLatitude), 7), round(_compound_degrees(site.RefLongitude), 7),
                        _true_north(model))
    return None


def _style_of(model, material):
    """The IfcSurfaceStyle (or material) of an IfcOpenShell style, or None
    for IfcOpenShell's defaults of unstyled products (instance 0)."""
    if material.instance_id() <= 0:
        return None
    try:
        entity = model.by_id(material.instance_id())
    except RuntimeError:
        return None
    if entity.is_a("IfcSurfaceStyleShading"):
        for style in model.get_inverse(entity):
            if style.is_a("IfcSurfaceStyle"):
                return style
    return entity


def _glass_transmittance(model, material):
    """(r, g, b) for a style that is glass: transparent (IFC: Transparency 0
    is opaque, 1 fully transparent; the colour is the surface's own, which
    viewers blend with what lies behind, so it does not tint), or named as
    glass. A TransmissionColour, where the style gives one, is the tint."""
    style = _style_of(model, material)
    if style is None:
        return None
    transparency = float(material.transparency) if material.transparency == material.transparency else 0.0
    named = GLASS_NAME.search(getattr(style, "Name", None) or "") or GLASS_NAME.search(material.name or "")
    if transparency <= 0 and not named:
        return None
    transparency = transparency if transparency > 0 else NAMED_GLASS_TRANSPARENCY
    tint = (1.0, 1.0, 1.0)
    for shading in getattr(style, "Styles", None) or ():
        colour = getattr(shading, "TransmissionColour", None)
        if colour is None:
            continue
        if hasattr(colour, "Red"):
            tint = (colour.Red, colour.Green, colour.Blue)
        else:
            base = shading.SurfaceColour
            tint = tuple(colour.wrappedValue * c for c in (base.Red, base.Green, base.Blue))
    transmittance = tuple(round(min(1.0, max(0.0, transparency * c)), 4) for c in tint)
    return transmittance if max(transmittance) > 0 else None


def _triangle_materials(geometry, materials, count):
    """(count,) indices into `materials` of each triangle's style."""
    ids = [materials.add(m.name, _style_albedo(m)) for m in geometry.materials]
    per_triangle = np.asarray(geometry.material_ids, dtype=np.int64)
    if ids and len(per_triangle) == count:
        lookup = np.asarray(ids, dtype=np.int64)
        return np.where(per_triangle >= 0, lookup[np.clip(per_triangle, 0, len(ids) - 1)], 0)
    return np.zeros(count, dtype=np.int64)


def _read_window(model, product, geometry, mesh, materials, result):
    """A window's glass becomes a Glazing, the rest (frames, sashes) an
    element; a window without glass is left out, its hole open."""
    name = product.Name or product.GlobalId
    glass_of = [_glass_transmittance(model, m) for m in geometry.materials]
    per_triangle = np.asarray(geometry.material_ids, dtype=np.int64)
    if len(per_triangle) != len(mesh.triangles) or not any(glass_of):
        result.unglazed_windows.append(name)
        return
    is_glass = np.array([k >= 0 and glass_of[k] is not None for k in per_triangle])
    if not is_glass.any():
        result.unglazed_windows.append(name)
        return
    # The tint of the glass style with the most triangles.
    counts = np.bincount(per_triangle[is_glass], minlength=len(glass_of))
    transmittance = glass_of[int(np.argmax(counts))]
    result.glazings.append(Glazing(name, product.GlobalId, Mesh(mesh.vertices, mesh.triangles[is_glass]), transmittance))
    if (~is_glass).any():
        frame = Mesh(mesh.vertices, mesh.triangles[~is_glass])
        of_triangle = _triangle_materials(geometry, materials, len(mesh.triangles))[~is_glass]
        result.elements.append(Element(product.is_a(), name, product.GlobalId, frame, of_triangle))


def read_ifc(path, glazing=True):
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
    windows = {p.id() for p in model.by_type("IfcWindow")} if glazing else set()
    curtain_plates = {p.id() for p in model.by_type("IfcPlate") if _in_curtain_wall(p)} if glazing else set()
    # Voids nothing fills: holes the model leaves open on purpose or by mistake (reported).
    unfilled = {o.id(): _host_of(o) for o in model.by_type("IfcOpeningElement")
                if o.id() not in holes and not getattr(o, "HasFillings", None)}
    fillers = {filled.id() for filled, _, _ in holes.values()}
    wanted = (surfaces + list(model.by_type("IfcSpace")) + [model.by_id(i) for i in holes] +
              [model.by_id(i) for i in windows] + [model.by_id(i) for i in unfilled] + [model.by_id(i) for i in fillers])
    wanted = [p for p in {p.id(): p for p in wanted if p.Representation is not None}.values()]

    filler_bounds, holes_found = {}, set()
    for product, geometry in _iterate_shapes(model, wanted):
        vertices = to_portico_axes(geometry.verts)
        triangles = np.asarray(geometry.faces, dtype=np.int64).reshape(-1, 3)
        if len(triangles) == 0:
            continue
        mesh = Mesh(vertices, triangles)
        name = product.Name or product.GlobalId
        if product.id() in fillers:
            filler_bounds[product.id()] = mesh.bounds()
            if product.id() not in holes and product.id() not in windows:
                continue
        if product.id() in holes:
            holes_found.add(product.id())
            filled, kind, host = holes[product.id()]
            lo, hi = mesh.bounds()
            result.openings.append(Opening(kind, filled.Name or filled.GlobalId, lo, hi, host, filler=filled.GlobalId))
        if product.id() in unfilled:
            lo, hi = mesh.bounds()
            result.unfilled_openings.append(Opening("unfilled", name, lo, hi, unfilled[product.id()]))
            continue
        if product.id() in curtain_plates:
            result.glazings.append(Glazing(name, product.GlobalId, mesh, _curtain_transmittance(model, geometry),
                                           curtain=True))
            continue
        if product.id() in windows:
            _read_window(model, product, geometry, mesh, materials, result)
        if product.is_a("IfcSpace"):
            label = " ".join(x for x in (product.Name, product.LongName) if x) or product.GlobalId
            result.spaces.append(Space(label, product.GlobalId, mesh))
            continue
        if product.id() in holes or product.id() in windows:
            continue
        if product.id() in fixtures:
            lo, hi = mesh.bounds()
            result.fixtures.append(Fixture(name, lo, hi, _fixture_watts(product), _fixture_lumens(product),
                                           _fixture_kelvin(product)))
        of_triangle = _triangle_materials(geometry, materials, len(triangles))
        result.elements.append(Element(product.is_a(), name, product.GlobalId, mesh, of_triangle,
                                       sealing=any(product.is_a(t) for t in SEALING_TYPES)))
    # An opening element IfcOpenShell cannot tessellate (some exporters write
    # attributes it refuses): the door's or window's own box stands for its hole.
    for key, (filled, kind, host) in holes.items():
        if key not in holes_found and filled.id() in filler_bounds:
            lo, hi = filler_bounds[filled.id()]
            result.openings.append(Opening(kind, filled.Name or filled.GlobalId, lo, hi, host, filler=filled.GlobalId))
    element_bounds = {e.guid: e.mesh.bounds() for e in result.elements}
    for o in result.openings + result.unfilled_openings:
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
    result.unfilled_openings.sort(key=lambda o: (o.name, tuple(o.lo)))
    result.fixtures.sort(key=lambda f: (f.name, tuple(f.lo)))
    result.glazings.sort(key=lambda g: (g.guid, g.name))
    result.unglazed_windows.sort()
    result.site = _site(model)
    return result
