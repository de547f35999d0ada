"""The tables of a scene file read into the :mod:`meicp.scene` dataclasses, and the checks of
values that are each in range but not together (:meth:`SceneParser.magnitudes`).  Single
values are checked by :mod:`meicp.io.scene_values`."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from ..core.validation import MAX_TOL
from ..scene import (BOUNDARY_KINDS, CONTACT, INTERFACE_KINDS, SIDES, SOLVE, Boundary, Contact, Damping,
                     Embedded, FrozenOptions, Interface, Lattice, Layer, Load, Scene, Solver)
from .scene_values import KEYS, Table, ValueChecks, fmt_value

#: the smallest normal double: a node mass below it loses precision, 0 makes B singular
TINY = 2.2250738585072014e-308
#: the largest ratio of two bond stiffnesses in one scene: where a bond of stiffness k meets
#: one of k·C, the first keeps about 16 − log10(C) digits in K (double precision); with the
#: stiff layer floating on the base, two_layers.toml gives the same verdict up to C = 1e12
#: and σ < 0 "modes" from 1e14 on
MAX_STIFFNESS_CONTRAST = 1e12


class SceneParser(ValueChecks):
    """Reads a parsed scene table (:meth:`parse`) table by table."""

    # ---------------------------------------------------------------- the whole scene
    def parse(self, data) -> Scene:
        top = Table(self, data, "", KEYS[""])
        title = top.string("title", "")
        lattice = self.lattice(top.raw("lattice"))
        top.used.update({"layers", "embedded", "interfaces"})
        layers = self.layers(data, lattice)
        embedded = self.embedded(data, lattice, layers)
        interfaces = self.interfaces(data, lattice, layers)
        boundary = self.boundary(top.raw("boundary", {}))
        contact_data = top.raw("contact", None)
        contact = None
        if contact_data is not None:
            contact = self.contact(contact_data, lattice)
        if boundary.bottom == CONTACT and contact is None:
            self.fail("contact", "is required when boundary.bottom = \"contact\" "
                                 "(give at least contact.friction)")
        if contact is not None and boundary.bottom != CONTACT:
            self.fail("contact", f"describes the rigid base, but boundary.bottom is "
                                 f"{boundary.bottom!r}, not \"contact\"")
        load_data = top.raw("load", None)
        load = None if load_data is None else self.load(load_data, boundary)
        damping_data = top.raw("damping", None)
        damping = None if damping_data is None else self.damping(damping_data)
        solver = self.solver(top.raw("solver", {}))
        petsc = self.petsc(top.raw("petsc", {}))
        top.done()
        ny = sum(layer.rows for layer in layers)
        if ny * lattice.nx * 2 >= 2**62:
            self.fail("layers", f"declare {ny} rows x {lattice.nx} columns: too many DOFs")
        self.magnitudes(lattice, ny, layers, embedded, interfaces, contact, load)
        self.damping_magnitudes(lattice, layers, embedded, damping)
        return Scene(lattice=lattice, layers=tuple(layers), boundary=boundary,
                     interfaces=tuple(interfaces), embedded=tuple(embedded), contact=contact,
                     load=load, damping=damping, solver=solver, petsc=petsc, title=title, source=self.source)

    def lattice(self, data) -> Lattice:
        t = Table(self, data, "lattice", KEYS["lattice"])
        nx = t.integer("nx", minimum=2)
        spacing = t.number("spacing", 1.0, positive=True)
        shear = t.number("shear", 0.0)
        kab = t.raw("interface_stiffness", "mean")
        if isinstance(kab, str):
            if kab != "mean":
                self.fail("lattice.interface_stiffness", f"must be \"mean\" or a number > 0, got {kab!r}")
        else:
            kab = self.check_number("lattice.interface_stiffness", kab, positive=True)
        t.done()
        return Lattice(nx=nx, spacing=spacing, shear=shear, interface_stiffness=kab)

    def layers(self, data, lattice) -> list[Layer]:
        if "layers" not in data:
            self.fail("layers", "is required: at least one [[layers]] table, bottom to top")
        entries = self.array_of_tables(data, "layers")
        if not entries:
            self.fail("layers", "must have at least one [[layers]] table")
        layers, names = [], set()
        for k, entry in enumerate(entries):
            t = Table(self, entry, f"layers[{k}]", KEYS["layers"])
            name = self.new_name(t, names, "the layer name")
            layer = Layer(name=name, rows=t.integer("rows", minimum=1),
                          stiffness=t.number("stiffness", positive=True),
                          density=t.number("density", positive=True),
                          viscosity=t.number("viscosity", None, nonnegative=True))
            t.done()
            layers.append(layer)
        return layers

    def new_name(self, t, names: set, what: str, why: str = "") -> str:
        """Table ``t``'s non-empty ``name``, not among ``names`` (added to them)."""
        name = t.string("name")
        if not name:
            self.fail(t.key("name"), "must not be empty")
        if name in names:
            self.fail(t.key("name"), f"repeats {what} {name!r}{why}")
        names.add(name)
        return name

    def embedded(self, data, lattice, layers) -> list[Embedded]:
        entries = self.array_of_tables(data, "embedded")
        by_name = {layer.name: layer for layer in layers}
        out, names, boxes = [], set(by_name), []
        for k, entry in enumerate(entries):
            t = Table(self, entry, f"embedded[{k}]", KEYS["embedded"])
            name = self.new_name(t, names, "the name", " (layer and band names are unique)")
            host = t.string("host")
            if host not in by_name:
                self.fail(t.key("host"), f"must name a layer ({', '.join(map(repr, by_name))}), got {host!r}")
            hrows = by_name[host].rows
            row = t.integer("row", 0, minimum=0)
            rows = t.integer("rows", 1, minimum=1)
            if row + rows > hrows:
                self.fail(t.key("rows"), f"row + rows = {row + rows} exceeds the {hrows} rows of layer {host!r}")
            column = t.integer("column", 0, minimum=0)
            if column >= lattice.nx:
                self.fail(t.key("column"), f"must be < nx = {lattice.nx}, got {column}")
            columns = t.integer("columns", lattice.nx - column, minimum=1)
            if column + columns > lattice.nx:
                self.fail(t.key("columns"), f"column + columns = {column + columns} exceeds nx = {lattice.nx}")
            stiffness = t.number("stiffness", positive=True)
            density = t.number("density", positive=True)
            kab = t.number("interface_stiffness", None, positive=True)
            if kab is None:
                kab = lattice.pair_stiffness(stiffness, by_name[host].stiffness)
            viscosity = t.number("viscosity", None, nonnegative=True)
            t.done()
            box = (host, row, row + rows, column, column + columns)
            for other_k, other in boxes:
                if (other[0] == host and box[1] < other[2] and other[1] < box[2]
                        and box[3] < other[4] and other[3] < box[4]):
                    self.fail(f"embedded[{k}]", f"overlaps embedded[{other_k}] in layer {host!r}")
            boxes.append((k, box))
            out.append(Embedded(name=name, host=host, stiffness=stiffness, density=density,
                                row=row, rows=rows, column=column, columns=columns,
                                interface_stiffness=kab, viscosity=viscosity))
        return out

    def interfaces(self, data, lattice, layers) -> list[Interface]:
        entries = self.array_of_tables(data, "interfaces")
        index = {layer.name: k for k, layer in enumerate(layers)}
        declared: dict[int, Interface] = {}
        for k, entry in enumerate(entries):
            t = Table(self, entry, f"interfaces[{k}]", KEYS["interfaces"])
            below = t.string("below")
            if below not in index:
                self.fail(t.key("below"), f"must name a layer ({', '.join(map(repr, index))}), got {below!r}")
            i = index[below]
            if i == len(layers) - 1:
                self.fail(t.key("below"), f"names the top layer {below!r}: there is no layer above it")
            if i in declared:
                self.fail(t.key("below"), f"repeats the interface above layer {below!r}")
            kind = t.string("kind", "bonded", INTERFACE_KINDS)
            if kind == "bonded":
                for bad in ("friction", "states"):
                    if bad in entry:
                        self.fail(t.key(bad), "applies to kind = \"frictional\" only")
                stiffness = t.number("stiffness", None, positive=True)
                if stiffness is None:
                    stiffness = lattice.pair_stiffness(layers[i].stiffness, layers[i + 1].stiffness)
                itf = Interface(below=below, index=i, kind=kind, stiffness=stiffness,
                                viscosity=t.number("viscosity", None, nonnegative=True), declared=True)
            else:
                for bad in ("stiffness", "viscosity"):
                    if bad in entry:
                        self.fail(t.key(bad), "applies to kind = \"bonded\" only "
                                              "(a frictional interface has no bonds)")
                friction = t.number("friction", positive=False, nonnegative=True)
                states = self.states(t.key("states"), t.raw("states", SOLVE), lattice.nx)
                itf = Interface(below=below, index=i, kind=kind, friction=friction,
                                states=states, declared=True)
            t.done()
            declared[i] = itf
        out = []
        for i in range(len(layers) - 1):
            out.append(declared.get(i) or Interface(
                below=layers[i].name, index=i, kind="bonded",
                stiffness=lattice.pair_stiffness(layers[i].stiffness, layers[i + 1].stiffness)))
        return out

    def boundary(self, data) -> Boundary:
        t = Table(self, data, "boundary", KEYS["boundary"])
        values = {}
        for side in SIDES:
            choices = BOUNDARY_KINDS + ((CONTACT,) if side == "bottom" else ())
            values[side] = t.string(side, "free", choices)
        t.done()
        return Boundary(**values)

    def contact(self, data, lattice) -> Contact:
        t = Table(self, data, "contact", KEYS["contact"])
        friction = t.number("friction", nonnegative=True)
        states = self.states("contact.states", t.raw("states", SOLVE), lattice.nx)
        t.done()
        return Contact(friction=friction, states=states)

    def load(self, data, boundary) -> Load:
        t = Table(self, data, "load", KEYS["load"])
        top = t.raw("top_displacement", None)
        if top is not None:
            if not isinstance(top, list) or len(top) != 2:
                self.fail("load.top_displacement", f"must be a list of 2 numbers [ux, uy], got {fmt_value(top)}")
            top = tuple(self.check_number(f"load.top_displacement[{k}]", v) for k, v in enumerate(top))
            if boundary.top == "free":
                self.fail("load.top_displacement", "needs a top boundary that is fixed "
                                                   "(boundary.top is \"free\")")
        side = t.raw("side_displacement", None)
        if side is not None:
            if not isinstance(side, list) or len(side) != 2:
                self.fail("load.side_displacement", f"must be a list of 2 numbers [left_ux, right_ux], "
                                                    f"got {fmt_value(side)}")
            side = tuple(self.check_number(f"load.side_displacement[{k}]", v) for k, v in enumerate(side))
            for k, name in enumerate(("left", "right")):
                if side[k] != 0.0 and not boundary.fixed_components(name)[0]:
                    self.fail("load.side_displacement", f"prescribes x = {side[k]:g} on the {name} side, "
                              f"which needs boundary.{name} = \"fixed\" or \"fixed_x\" "
                              f"(it is {getattr(boundary, name)!r})")
        gravity = t.number("gravity", 0.0)
        t.done()
        return Load(top_displacement=top, gravity=gravity, side_displacement=side)

    def damping(self, data) -> Damping:
        t = Table(self, data, "damping", KEYS["damping"])
        mass = t.number("mass", 0.0, nonnegative=True)
        t.done()
        return Damping(mass=mass)

    def damping_magnitudes(self, lattice, layers, embedded, damping) -> None:
        """Damping values each finite alone whose products are not: the mass term α·ρ·a³ of
        ``[damping] mass`` (each viscosity enters C alone, as a stiffness enters K)."""
        if damping is None or not damping.mass:
            return
        cube = lattice.spacing ** 3
        densities = [m.density for m in layers] + [e.density for e in embedded]
        if not math.isfinite(damping.mass * max(densities) * cube):
            self.fail("damping.mass", f"= {damping.mass:g} times the largest node mass ρ·a³ = "
                                      f"{max(densities) * cube:g} overflows")

    def solver(self, data) -> Solver:
        t = Table(self, data, "solver", KEYS["solver"])
        method = t.string("method", "auto")
        if not method:
            self.fail("solver.method", "must not be empty")
        s = Solver(method=method,
                   all_solutions=t.boolean("all_solutions", False),
                   lam_min=t.number("lam_min", None, nonnegative=True),
                   nev=t.integer("nev", None, minimum=1),
                   tol=t.number("tol", None, positive=True),
                   max_iterations=t.integer("max_iterations", None, minimum=1),
                   flutter=t.boolean("flutter", True))
        t.done()
        if s.tol is not None and s.tol > MAX_TOL:
            self.fail("solver.tol", f"must be <= {MAX_TOL:g} (a relative certificate tolerance; a looser "
                                    f"one certifies nothing), got {s.tol:g}")
        return s

    def magnitudes(self, lattice, ny: int, layers, embedded, interfaces, contact, load) -> None:
        """Values each in range alone but not together: coordinates and node masses must be
        finite normal floats, and the bond stiffnesses (and a friction coefficient, which
        multiplies them in a slipping node's row) within MAX_STIFFNESS_CONTRAST of each
        other."""
        a = lattice.spacing
        extent = max(lattice.nx - 1 + abs(lattice.shear) * (ny - 1), ny - 1, 1)
        if not math.isfinite(a * extent) or not math.isfinite(a * math.hypot(1.0, lattice.shear)):
            self.fail("lattice.spacing", f"= {a:g} with nx = {lattice.nx}, {ny} rows and shear = "
                                         f"{lattice.shear:g} puts nodes beyond double precision")
        cube = a * a * a  # the mass per unit density; a ** 3 would raise OverflowError
        if not (math.isfinite(cube) and cube >= TINY):
            self.fail("lattice.spacing", f"= {a:g}: the node mass per unit density a³ = {cube:g} is beyond "
                                         "double precision (a must lie in about [3e-103, 5e102])")
        masses = [(f"layers[{k}].density", m.density) for k, m in enumerate(layers)]
        masses += [(f"embedded[{k}].density", e.density) for k, e in enumerate(embedded)]
        for key, rho in masses:
            mass = rho * cube
            if not (math.isfinite(mass) and mass >= TINY):
                self.fail(key, f"= {rho:g} with lattice.spacing = {a:g} gives a node mass ρ·a³ = {mass:g}, "
                               "beyond double precision (it must lie in [2.2e-308, 1.8e308])")
            if load is not None and not math.isfinite(load.gravity * mass):
                self.fail("load.gravity", f"= {load.gravity:g} times the node mass of {key} overflows")
        stiff = [(f"layers[{k}].stiffness", m.stiffness) for k, m in enumerate(layers)]
        stiff += [(f"embedded[{k}].stiffness", e.stiffness) for k, e in enumerate(embedded)]
        stiff += [(f"embedded[{k}].interface_stiffness", e.interface_stiffness) for k, e in enumerate(embedded)]
        stiff += [(f"interfaces.stiffness (below = {i.below!r})", i.stiffness) for i in interfaces
                  if i.bonded and i.declared]
        if not isinstance(lattice.interface_stiffness, str):
            stiff.append(("lattice.interface_stiffness", lattice.interface_stiffness))
        (k_lo, lo), (k_hi, hi) = min(stiff, key=lambda t: t[1]), max(stiff, key=lambda t: t[1])
        if hi > MAX_STIFFNESS_CONTRAST * lo:
            self.fail(k_lo, f"= {lo:g} and {k_hi} = {hi:g} differ by {hi / lo:.1e}, more than "
                            f"{MAX_STIFFNESS_CONTRAST:.0e}: the softer bonds are lost in the rounding of "
                            "the stiffer ones where they meet (measured: wrong modes from 1e14 on); model a "
                            "rigid part with fixed boundary conditions instead")
        frictions = [("contact.friction", contact.friction)] if contact is not None else []
        frictions += [(f"interfaces.friction (below = {i.below!r})", i.friction) for i in interfaces
                      if not i.bonded]
        for key, mu in frictions:
            if mu > MAX_STIFFNESS_CONTRAST:
                self.fail(key, f"= {mu:g} is above {MAX_STIFFNESS_CONTRAST:.0e}: a slipping node's row sums "
                               "μ times the normal stiffness and the tangential one, which would be lost in "
                               "rounding (measured: spurious modes at μ = 1e300)")

    def petsc(self, data) -> Mapping[str, Any]:
        if not isinstance(data, Mapping):
            self.fail("petsc", f"must be a table, got {fmt_value(data)}")
        out = {}
        for key, value in data.items():
            if isinstance(value, (Mapping, list)) or not isinstance(value, (str, int, float, bool)):
                self.fail(f"petsc.{key}", f"must be a string, number or boolean, got {fmt_value(value)}")
            if isinstance(value, float) and not math.isfinite(value):
                self.fail(f"petsc.{key}", f"must be finite, got {value}")
            name = key.lstrip("-")
            if not name or any(c.isspace() for c in name):
                self.fail(f"petsc.{key}", "is not a valid PETSc option name")
            out[name] = value
        return FrozenOptions(out)
