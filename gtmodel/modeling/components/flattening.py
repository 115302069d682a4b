"""Flattening of a component tree into a :class:`~gtmodel.modeling.Model` (internal to components).

:meth:`gtmodel.modeling.components.component.Component.to_model` runs one :class:`_Flattening`:

1. walk the tree (pre-order), declare every parameter, variable and connector variable
   in a scratch model under its hierarchical name, and bind the symbols to the instances;
2. run every component's ``equations()`` (recording equations, outputs, connections and
   :meth:`~gtmodel.modeling.components.component.Component.model_call` calls);
3. build the connection sets per hierarchy level (inside connectors +1, outside -1),
   write equal potentials and flow sums, zero flows of unconnected connectors, and drop
   the potentials no equation uses in their whole cross-level class;
4. declare the kept variables in the final model and substitute the scratch symbols.

The Modelica Language Specification 3.6, section 9.2 (connection equations), is the
reference for step 3.
"""

from __future__ import annotations

import logging
import re
from dataclasses import dataclass, field
from typing import Any

import casadi as ca

from gtmodel.errors import GtModelError, InputError, ModelError
from gtmodel.modeling.components.connectors import Connector
from gtmodel.modeling.dae import _as_sx
from gtmodel.modeling.components.declarations import Parameter, Variable, _ComponentBase, _declarations
from gtmodel.modeling.simulation.model import Model

__all__: list[str] = []

_log = logging.getLogger("gtmodel")

#: The component whose equations() runs, with its flattening (for module-level connect()).
_ACTIVE: list[tuple["_Flattening", Any]] = []


@dataclass
class _Declared:
    """A variable declared in the scratch model (internal record)."""

    name: str
    kind: str
    sym: ca.SX
    size: int
    start: Any = None
    lb: Any = None
    ub: Any = None
    value: Any = None
    fixed: Any = None
    unit: str = ""
    smoothing: bool = False


@dataclass
class _Flattening:
    """One flattening of a component tree into a Model (internal)."""

    root: _ComponentBase
    name: str
    scratch: Model = field(init=False)
    declared: list[_Declared] = field(default_factory=list)
    equations: list[tuple[_ComponentBase, str, ca.SX]] = field(default_factory=list)
    outputs: list[tuple[str, ca.SX]] = field(default_factory=list)
    output_units: dict[str, str] = field(default_factory=dict)
    pairs: dict[int, list[tuple[Connector, Connector]]] = field(default_factory=dict)
    nodes: list[_ComponentBase] = field(default_factory=list)
    calls: list[tuple[_ComponentBase, str, tuple, dict, Any]] = field(default_factory=list)
    known: set[int] = field(default_factory=set)

    def __post_init__(self) -> None:
        self.scratch = Model(self.name)
        self.known.add(self.scratch.time.element_hash())

    # -------------------------------------------------------------- declarations
    def _declare(self, full: str, kind: str, size: int, **attrs: Any) -> ca.SX:
        m = self.scratch
        if kind == "parameter":
            sym = m.parameter(full, attrs["value"], smoothing=attrs.get("smoothing", False))
        else:
            extra = {} if kind == "input" or attrs.get("fixed") is None else {"fixed": attrs["fixed"]}
            sym = getattr(m, kind)(full, shape=size, start=attrs.get("start"), lb=attrs.get("lb"), ub=attrs.get("ub"),
                                   unit=attrs.get("unit") or "", **extra)
        self.declared.append(_Declared(full, kind, sym, size, **attrs))
        self.known.update(sym[i].element_hash() for i in range(size))
        if kind == "state":
            der = self.scratch.der(sym)
            self.known.update(der[i].element_hash() for i in range(size))
        return sym

    def _walk(self, comp: _ComponentBase, path: str) -> None:
        comp._path, comp._ctx, comp._symbols = path, self, {}
        self.nodes.append(comp)
        pre = f"{path}." if path else ""
        try:
            for name, decl in _declarations(type(comp)).items():
                if isinstance(decl, Parameter):
                    value = comp._values[name]
                    if isinstance(value, Parameter):
                        owner = comp.parent
                        if owner is None or _declarations(type(owner)).get(value.name) is not value:
                            raise ModelError(
                                f"parameter {name!r} is bound to a Parameter ({value.name or 'unnamed'}) that is not "
                                "declared by the enclosing component"
                            )
                        comp._symbols[name] = owner._symbols[value.name]
                        if decl.smoothing:  # bound to a smoothing width: the enclosing parameter is one
                            self._mark_smoothing(comp._symbols[name], f"{pre}{name} (bound to {value.name})")
                    else:
                        comp._symbols[name] = self._declare(pre + name, "parameter", decl.size, value=value,
                                                            smoothing=decl.smoothing)
                elif isinstance(decl, Variable):
                    comp._symbols[name] = self._declare(pre + name, decl.kind, decl.size, **comp._attributes[name],
                                                        unit=decl.unit or "")
            for cname, conn in comp.connectors().items():
                conn._symbols = {v.name: self._declare(f"{pre}{cname}.{v.name}", "algebraic", v.size, unit=v.unit or "")
                                 for v in conn.variables()}
        except GtModelError as exc:
            raise ModelError(f"component {comp._label()}: {exc}") from None
        for sname, sub in comp.components().items():
            self._walk(sub, pre + sname)

    def _mark_smoothing(self, sym: ca.SX, where: str) -> None:
        """Mark the declared parameter ``sym`` a smoothing width (a sub-component's width is bound to it)."""
        d = next(d for d in self.declared if d.kind == "parameter" and d.size == 1 and d.sym.element_hash() == sym.element_hash())
        if not d.smoothing:
            Parameter(d.value, smoothing=True).validate(d.value, where)  # one number > 0
            d.smoothing = True

    # -------------------------------------------------------------- used by components
    def equation(self, comp: _ComponentBase, lhs: Any, rhs: Any, name: str | None) -> None:
        k = sum(1 for c, _, _ in self.equations if c is comp)
        label = f"{comp.path}.{name or f'eq{k}'}" if comp.path else (name or f"eq{k}")
        a = _as_sx(lhs, f"equation {label!r} lhs")
        b = _as_sx(rhs, f"equation {label!r} rhs")
        if a.numel() != b.numel() and a.numel() != 1 and b.numel() != 1:
            raise InputError(f"component {comp._label()}: equation {label!r}: lhs has {a.numel()} elements but rhs has {b.numel()}")
        res = a - b
        self._check_symbols(res, f"component {comp._label()}: equation {label!r}")
        self.equations.append((comp, label, res))

    def _check_symbols(self, expr: ca.SX, what: str) -> None:
        """Like :meth:`Model.check_symbols`, by element hashes (O(1) per symbol)."""
        if any(v.element_hash() not in self.known for v in ca.symvar(expr)):
            # symbols declared on the scratch model by other means (model_call, event passes)
            self.scratch.check_symbols(expr, what)

    def output(self, comp: _ComponentBase, name: str, expr: Any, unit: str = "") -> None:
        full = f"{comp.path}.{name}" if comp.path else name
        if not isinstance(unit, str):
            raise InputError(f"component {comp._label()}: output {full!r} unit: expected a string such as 'N', got {unit!r}")
        if unit:
            self.output_units[full] = unit
        e = _as_sx(expr, f"output {full!r}")
        self._check_symbols(e, f"component {comp._label()}: output {full!r}")
        if any(n == full for n, _ in self.outputs):
            raise ModelError(f"component {comp._label()}: output {full!r} is declared twice")
        self.outputs.append((full, e))

    def model_call(self, comp: _ComponentBase, method: str, args: tuple, kwargs: dict) -> Any:
        fn = getattr(self.scratch, method, None) if isinstance(method, str) and not method.startswith("_") else None
        if not callable(fn):
            raise ModelError(f"component {comp._label()}: model_call: {method!r} is not a public method of Model")
        ret = fn(*args, **kwargs)
        self.calls.append((comp, method, args, kwargs, ret))
        return ret

    def connect(self, comp: _ComponentBase, a: Any, b: Any) -> None:
        where = f"component {comp._label()}: connect({getattr(a, 'path', a)}, {getattr(b, 'path', b)})"
        for c in (a, b):
            if not isinstance(c, Connector):
                raise ModelError(f"{where}: {c!r} is not a connector (got {type(c).__name__})")
        if a is b:
            raise ModelError(f"{where}: a connector cannot be connected to itself")
        for c in (a, b):
            if c.owner is not comp and c.owner.parent is not comp:
                raise ModelError(
                    f"{where}: connector {c.path} belongs neither to {comp.path or '<root>'} nor to one of its direct "
                    "sub-components"
                )
        if a.signature() != b.signature():
            raise ModelError(
                f"{where}: incompatible connectors {a.path} ({type(a).__name__}: "
                f"{', '.join(v.name for v in a.variables())}) and {b.path} ({type(b).__name__}: "
                f"{', '.join(v.name for v in b.variables())})"
            )
        self.pairs.setdefault(id(comp), []).append((a, b))

    # -------------------------------------------------------------- the flattening
    def run(self) -> Model:
        root = self.root
        try:
            self._walk(root, "")
            for comp in self.nodes:
                _ACTIVE.append((self, comp))
                try:
                    comp.equations()
                except GtModelError as exc:
                    raise type(exc)(str(exc) if comp._label() in str(exc) else f"component {comp._label()}: {exc}") from None
                except (RuntimeError, TypeError, ValueError, NotImplementedError, AttributeError) as exc:
                    raise ModelError(f"component {comp._label()}: error in equations(): {_short(exc)}") from None
                finally:
                    _ACTIVE.pop()
            return self._build()
        finally:
            for comp in self.nodes:
                comp._ctx = None
                comp._path = None

    def _build(self) -> Model:
        sets, inside_connected = self._connection_sets()
        used = self._used_names()
        # potentials dropped when unused in their whole cross-level class (union of sets)
        parent: dict[int, int] = {}

        def find(i: int) -> int:
            while parent.setdefault(i, i) != i:
                parent[i] = parent[parent[i]]
                i = parent[i]
            return i

        for members in sets:
            for conn, _ in members[1:]:
                parent[find(id(conn))] = find(id(members[0][0]))
        classes: dict[int, list[Connector]] = {}
        all_conns = [c for comp in self.nodes for c in comp.connectors().values()]
        for conn in all_conns:
            classes.setdefault(find(id(conn)), []).append(conn)
        dropped: set[str] = set()
        for members in classes.values():
            for var in members[0].variables():
                if var.is_flow:
                    continue
                names = [_element_names(c._symbols[var.name]) for c in members]
                if not any(n in used for ns in names for n in ns):
                    dropped.update(f"{c.path}.{var.name}" for c in members)
        eqs: list[tuple[str, ca.SX]] = [(label, res) for _, label, res in self.equations]
        for members in sets:
            label = "connect(" + ", ".join(c.path for c, _ in members) + ")"
            for var in members[0][0].variables():
                syms = [c._symbols[var.name] for c, _ in members]
                if var.is_flow:
                    eqs.append((f"{label}.{var.name}", sum((sign * s for (c, sign), s in zip(members, syms)), ca.SX.zeros(var.size))))
                elif f"{members[0][0].path}.{var.name}" not in dropped:
                    eqs.extend((f"{label}.{var.name}[{k}]", syms[0] - s) for k, s in enumerate(syms[1:], 1))
        # flows of unconnected connectors are zero; so are those of the root's own connectors
        open_: list[str] = []
        for conn in all_conns:
            if conn.owner is self.root or id(conn) not in inside_connected:
                flows = [var for var in conn.variables() if var.is_flow]
                for var in flows:
                    eqs.append((f"{conn.path}.{var.name} (unconnected)", conn._symbols[var.name]))
                if flows and conn.owner is not self.root and id(conn) not in inside_connected and id(conn) in self._pure(conn.owner, True):
                    open_.append(f"{conn.path} ({', '.join(v.name for v in flows)} = 0)")
        model = self._final_model(eqs, dropped)
        parts = self._unconnected_parts()
        if parts:
            text = (f"component {self.name}: subsystem(s) that float (no connect() joins them to the rest, and none of "
                    f"their components fixes a potential as Ground or Fixed do): " + "; ".join("{" + ", ".join(p) + "}" for p in parts))
            _log.warning("%s", text)
            model.warnings.append(text)
        if open_:
            text = (f"component {self.name}: connector(s) left open (no connect(), so their flow is zero, as if nothing "
                    f"were attached): {', '.join(open_)}")
            _log.warning("%s", text)
            model.warnings.append(text)
        return model

    def _unconnected_parts(self) -> list[list[str]]:
        """Paths of the groups of sub-components that connect() joins, when there are several, that float (no reference in them)."""
        nodes = [c for c in self.nodes if c is not self.root and c.connectors()]
        parent = {id(c): id(c) for c in nodes}

        def find(i: int) -> int:
            while parent[i] != i:
                parent[i] = parent[parent[i]]
                i = parent[i]
            return i

        for pairs in self.pairs.values():
            for a, b in pairs:
                if id(a.owner) in parent and id(b.owner) in parent:
                    parent[find(id(a.owner))] = find(id(b.owner))
        groups: dict[int, list[_ComponentBase]] = {}
        for c in nodes:
            groups.setdefault(find(id(c)), []).append(c)
        parts = list(groups.values())
        if len(parts) < 2:
            return []
        # a part floats when no component of it fixes a potential (Ground's p.v = 0, Fixed's flange.phi = phi0)
        return [[c.path for c in part] for part in parts if not any(self._pure(c, False) for c in part)]

    def _pure(self, comp: _ComponentBase, flow: bool) -> set[int]:
        """Connectors of ``comp`` (by id) that one of its equations relates through their flows only
        (``flow``: two connectors or more, ``p.i + n.i = 0``, a gear's torques; an open one makes the
        component carry nothing) or whose potentials alone it fixes (not ``flow``: one connector, a
        reference such as ``p.v = 0``), with parameters and time."""
        params = {e.element_hash() for d in self.declared if d.kind == "parameter" for e in ca.symvar(d.sym)}
        params.add(self.scratch.time.element_hash())
        owner: dict[int, int] = {}
        for conn in comp.connectors().values():
            for var in conn.variables():
                if var.is_flow == flow:
                    owner.update({e.element_hash(): id(conn) for e in ca.symvar(conn._symbols[var.name])})
        found: set[int] = set()
        for c, _, res in self.equations:
            if c is not comp:
                continue
            hashes = [v.element_hash() for v in ca.symvar(res)]
            mine = [owner[h] for h in hashes if h in owner]
            # flows of two connectors or more (a balance), potentials of one connector (a fixed value)
            if mine and all(h in owner or h in params for h in hashes) and (len(set(mine)) > 1) == flow:
                found.update(mine)
        return found

    def _connection_sets(self) -> tuple[list[list[tuple[Connector, int]]], set[int]]:
        sets: list[list[tuple[Connector, int]]] = []
        inside_connected: set[int] = set()
        for comp in self.nodes:
            pairs = self.pairs.get(id(comp), [])
            groups: list[list[Connector]] = []
            for a, b in pairs:
                ga = next((g for g in groups if any(c is a for c in g)), None)
                gb = next((g for g in groups if any(c is b for c in g)), None)
                if ga is None and gb is None:
                    groups.append([a, b])
                elif ga is not None and gb is None:
                    ga.append(b)
                elif ga is None and gb is not None:
                    gb.append(a)
                elif ga is not gb:
                    ga.extend(gb)
                    groups.remove(gb)
            for g in groups:
                sets.append([(c, -1 if c.owner is comp else 1) for c in g])
                inside_connected.update(id(c) for c in g if c.owner is not comp)
            self._check_outside(comp, groups)
        return sets, inside_connected

    def _check_outside(self, comp: _ComponentBase, groups: list[list[Connector]]) -> None:
        """A composite's own connector must be connected inside it (or used by its equations)."""
        if not comp.components():
            return
        used = self._used_names(comp)
        for conn in comp.connectors().values():
            if any(c is conn for g in groups for c in g):
                continue
            if not any(n in used for v in conn.variables() for n in _element_names(conn._symbols[v.name])):
                raise ModelError(
                    f"component {comp._label()}: its connector {conn.path} is connected to nothing inside it"
                )

    def _used_names(self, only: _ComponentBase | None = None) -> set[str]:
        exprs = [res for comp, _, res in self.equations if only is None or comp is only]
        if only is None:
            exprs += [e for _, e in self.outputs]
            exprs += [e for call in self.calls for e in _sx_leaves(call[2:4])]
        if not exprs:
            return set()
        return {s.name() for s in ca.symvar(ca.vertcat(*exprs))}

    def _final_model(self, eqs: list[tuple[str, ca.SX]], dropped: set[str]) -> Model:
        model = Model(self.name)
        old, new = [self.scratch.time], [model.time]  # a component may use time in its equations
        for d in self.declared:
            if d.name in dropped:
                continue
            if d.kind == "parameter":
                sym = model.parameter(d.name, d.value, smoothing=d.smoothing)
            else:
                extra = {} if d.kind == "input" or d.fixed is None else {"fixed": d.fixed}
                sym = getattr(model, d.kind)(d.name, shape=d.size, start=d.start, lb=d.lb, ub=d.ub, unit=d.unit, **extra)
            old.append(d.sym)
            new.append(sym)
            if d.kind == "state":
                old.append(self.scratch.der(d.sym))
                new.append(model.der(sym))
        for comp, method, args, kwargs, ret in self.calls:
            o, n = ca.vertcat(*old), ca.vertcat(*new)

            def sub(v: Any) -> Any:
                if isinstance(v, ca.SX):
                    return ca.substitute(v, o, n)
                if isinstance(v, (list, tuple)):
                    return type(v)(sub(e) for e in v)
                if isinstance(v, dict):
                    return {k: sub(e) for k, e in v.items()}
                return v

            try:
                got = getattr(model, method)(*sub(args), **sub(kwargs))
            except GtModelError as exc:
                raise type(exc)(f"component {comp._label()}: model_call {method!r}: {exc}") from None
            if isinstance(ret, ca.SX) and isinstance(got, ca.SX) and ret.shape == got.shape and ret.is_symbolic():
                old.append(ca.vec(ret))
                new.append(ca.vec(got))
                if method == "state":
                    old.append(self.scratch.der(ret))
                    new.append(model.der(got))
        o, n = ca.vertcat(*old), ca.vertcat(*new)
        exprs = ca.substitute([r for _, r in eqs] + [e for _, e in self.outputs], [o], [n])
        for (label, _), res in zip(eqs, exprs[: len(eqs)]):
            model.equation(res, 0.0, name=label)
        for (oname, _), e in zip(self.outputs, exprs[len(eqs):]):
            model.output(oname, e, unit=self.output_units.get(oname, ""))
        _log.debug(
            "flattened component %s: %d variables (%d connector potentials dropped), %d equations",
            self.name, len(self.declared) - len(dropped), len(dropped), len(eqs),
        )
        return model


def _short(exc: Exception) -> str:
    """The informative line of an exception message (CasADi's last line, without its source path)."""
    lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
    if not lines:
        return type(exc).__name__
    return re.sub(r"^\.\.\./\S+:\d+:\s*", "", lines[-1])


def _sx_leaves(v: Any) -> list[ca.SX]:
    """The CasADi SX objects inside nested lists, tuples and dicts."""
    if isinstance(v, ca.SX):
        return [ca.vec(v)]
    if isinstance(v, (list, tuple)):
        return [e for x in v for e in _sx_leaves(x)]
    if isinstance(v, dict):
        return [e for x in v.values() for e in _sx_leaves(x)]
    return []


def _element_names(sym: ca.SX) -> list[str]:
    return [sym[i].name() for i in range(int(sym.numel()))]
