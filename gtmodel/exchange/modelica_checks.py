"""Modelica constructs that pymoca 0.12 reads as something else without a word, found in a file's text.

Each was tried on pymoca 0.12 itself (a small ``.mo`` file through ``pymoca.parser.parse`` and
``pymoca.backends.casadi.generator.generate``, as :func:`gtmodel.exchange.modelica.load_modelica`
does); what pymoca did is said with each entry of :data:`MISREAD`:

- a short class with a prefix, ``connector RealIn = input Real;`` (also ``output``, ``flow``,
  ``parameter``, ...): pymoca drops the prefix. A component ``RealIn u;`` is no input (an unused one
  disappears, a used one fails with a bare ``'u'``); ``type Gain = parameter Real;`` makes
  ``Gain k = 2;`` an algebraic variable with an equation ``k = 2``, no parameter.
- a short class with array dimensions, ``type Vec = Real[3];``: pymoca drops the dimensions; a
  component ``Vec x;`` is a scalar.
- a conditional component, ``Resistor r(R = 1) if useR;``: pymoca ignores the condition; the
  component and its equations are there also when ``useR = false`` (``Real x if false;``: an
  under-determined model).
- ``final``: pymoca keeps the value but not the finality; a modification from an enclosing class
  (``R r(k = 3)`` of ``final parameter Real k = 1`` in ``R``, or ``W w(r(k = 3))`` of ``R r(final
  k = 2)`` in ``W``) overrides it without an error. Whether one does is not decidable from the text,
  so ``final`` is accepted in the loaded class only (nothing modifies that one) and refused in the
  other classes of the file.
- a component redeclaration, ``Holder h(redeclare B a);`` of ``replaceable A a;``: pymoca merges ``B``
  into ``A`` (the variables and equations of both).
- an ``outer`` element: pymoca does not bind it to the ``inner`` one; it is a separate variable
  without a value or equation.
- an ``enumeration`` type: pymoca fails with a bare ``'Mode'``, without a line.
- a reduction expression (an array comprehension), ``sum(x[i]^2 for i in 1:3)`` (also ``product``,
  ``max``, ``{e for i in r}``): pymoca fails with a bare ``'i'``, without a line, when the iterator
  occurs in the expression; when it does not (``sum(1.0 for i in 1:3)``, ``sum(x[1] for i in 1:3)``)
  it reads the expression once (1.0, not 3.0). A ``for`` equation (``for i in 1:3 loop``) is not one.
- a ``Boolean`` or ``Integer`` variable (not a parameter or constant): pymoca reads it as a continuous
  Real variable, with no event at its changes (``Boolean on; on = time > 0.5;`` is a discontinuous
  algebraic equation the integrator stops on).

Handled correctly by pymoca 0.12, so accepted: short classes without a prefix or dimensions
(``type Voltage = Real(unit = "V", min = 0);`` with its ``unit``/``min``/``start`` kept, ``connector
PositivePin = Pin;``, ``model M = Base(k = 5);``), a class redeclaration (``replaceable model C = A;
C a;`` and ``redeclare model C = B``), ``replaceable`` components without a redeclaration, ``each``
on arrays of Reals, ``inner`` alone, ``protected``/``public``, Boolean and Integer parameters in
equations and ``if``-expressions, ``stateSelect``/``nominal``. ``stream`` fails in pymoca with a
message of its own (``Unsupported connector variable prefixes ['stream']``).
"""

from __future__ import annotations

import re

__all__ = ["MISREAD", "class_spans", "find_misread"]

_PREFIX = r"(?:input|output|flow|stream|parameter|constant|discrete)"
_CLASS_KW = r"(?:model|block|function|class|package|connector|record|type|optimization)"

#: Constructs pymoca 0.12 reads as something else: name -> (regex finding its line, what pymoca does, what to write instead).
MISREAD = {
    "short class with a prefix": (rf"\b{_CLASS_KW}\s+[A-Za-z_]\w*\s*=\s*{_PREFIX}\b",
                                  "pymoca 0.12 drops the prefix: a component of the class is no input/output/parameter",
                                  "write the prefix on the component (input Real u; parameter Real k = 1;)"),
    "short class with array dimensions": (rf"\b{_CLASS_KW}\s+[A-Za-z_]\w*\s*=\s*[A-Za-z_][\w.]*\s*\[",
                                          "pymoca 0.12 drops the dimensions: a component of the class is a scalar",
                                          "give the dimensions on the component (Real x[3];)"),
    "conditional component": (r"\bif\b(?:(?!\bthen\b)[^;])*;",
                              "pymoca 0.12 ignores the condition: the component is there also when it is false",
                              "declare the component unconditionally, or leave it out, or select its effect with a "
                              "parameter in the equations (k = if useR then R else 0)"),
    "final outside the loaded class": (r"\bfinal\b",
                                       "pymoca 0.12 keeps the value but not the final: a modification from an enclosing "
                                       "class overrides it without an error",
                                       "drop final and do not modify the element, or write the final value in the class you load"),
    "component redeclare": (rf"\bredeclare\s+(?:(?:replaceable|final|each)\s+)*(?!{_CLASS_KW}\b|replaceable\b|final\b|each\b)[A-Za-z_]",
                            "pymoca 0.12 merges the new class into the old one: the variables and equations of both are kept",
                            "redeclare a replaceable class instead (replaceable model C = A; C a; then redeclare model C = B), "
                            "or declare the component with the class you mean"),
    "outer element": (r"\bouter\b",
                      "pymoca 0.12 does not bind it to the inner element: it is a separate variable without a value or equation",
                      "pass the value down by a modification (Sub s(g = g))"),
    "enumeration type": (r"\benumeration\s*\(",
                         "pymoca 0.12 cannot translate it",
                         "use an Integer parameter with a constant for each value"),
    "reduction expression": (r"\bfor\s+[A-Za-z_]\w*\s+in\b(?:(?!\bloop\b)[^;])*;",
                             "pymoca 0.12 cannot translate it (a bare error naming the iterator) or, when the "
                             "iterator does not occur in the expression (sum(1.0 for i in 1:3)), reads it as the "
                             "expression once",
                             "write it with array operations (sum(x.^2) for sum(x[i]^2 for i in 1:3), "
                             "sum(x) for sum(x[i] for i in 1:3)) or as an explicit sum (x[1]^2 + x[2]^2 + x[3]^2)"),
    "Boolean or Integer variable": (rf"(?m)(?:^|;)[ \t]*(?:(?:input|output|flow|stream|discrete|inner|outer|final|replaceable|public|protected)\s+)*"
                                    r"(?:Boolean|Integer)\s*(?:\[[^\]]*\])?\s+[A-Za-z_]",
                                    "pymoca 0.12 reads it as a continuous Real variable, with no event where it changes",
                                    "use a parameter (parameter Boolean on = true;), or a Real variable with a smooth equation"),
}

_CLASS_RE = re.compile(rf"\bend\s+([A-Za-z_][\w.]*)\s*;|\b({_CLASS_KW})\s+([A-Za-z_]\w*)")


def class_spans(code: str) -> list[tuple[str, str, int, int]]:
    """The classes of a Modelica text, nested ones included, with their character ranges.

    Parameters
    ----------
    code : str
        Modelica source with comments and strings blanked (:func:`gtmodel.exchange.msl.code_only`).

    Returns
    -------
    list of tuple (str, str, int, int)
        ``(kind, dotted name, start, end)``: the keyword (``model``, ``function``, ...), the name
        from the outermost class on (``"Circuit.RC"``), and the range from the keyword to the end of
        ``end NAME;`` (of a short class ``type T = Real(...);``, to its ``;``). A class left open at
        the end of the text is not listed.
    """
    stack: list[tuple[str, str, int]] = []
    spans = []
    for m in _CLASS_RE.finditer(code):
        if m.group(1):  # "end NAME;" closes the class of that name
            if stack and stack[-1][1].split(".")[-1] == m.group(1).split(".")[-1]:
                kind, name, start = stack.pop()
                spans.append((kind, name, start, m.end()))
        elif code[max(0, m.start() - 4):m.start()].strip() != "end":
            name = f"{stack[-1][1]}.{m.group(3)}" if stack else m.group(3)
            if re.match(r"\s*=", code[m.end():]):  # a short class: no "end"
                semi = code.find(";", m.end())
                spans.append((m.group(2), name, m.start(), len(code) if semi < 0 else semi + 1))
            else:
                stack.append((m.group(2), name, m.start()))
    return spans


def _innermost(spans: list[tuple[str, str, int, int]], pos: int) -> tuple[str, str, int, int] | None:
    inside = [s for s in spans if s[2] <= pos < s[3]]
    return min(inside, key=lambda s: s[3] - s[2]) if inside else None


def _skip(what: str, code: str, m: re.Match[str], spans: list[tuple[str, str, int, int]], loaded: str | None) -> bool:
    """Whether a match of :data:`MISREAD` is the construct's harmless look-alike."""
    if what == "conditional component":
        return bool(re.search(r"\bend\s*$", code[max(0, m.start() - 40):m.start()]))  # "end if;"
    if what == "final outside the loaded class":
        cls = _innermost(spans, m.start())
        return loaded is not None and cls is not None and cls[1] == loaded
    if what == "Boolean or Integer variable":
        cls = _innermost(spans, m.end() - 1)
        return cls is not None and cls[0] == "function"  # a function's arguments and locals
    return False


def find_misread(code: str, loaded: str | None = None) -> list[tuple[int, str, str]]:
    """The constructs of :data:`MISREAD` in a Modelica text: the first line of each.

    Parameters
    ----------
    code : str
        Modelica source with comments and strings blanked (:func:`gtmodel.exchange.msl.code_only`),
        so that nothing in them counts.
    loaded : str, optional
        The dotted name of the class being translated (``"Circuit.RC"``): ``final`` is accepted
        inside it (and refused in any class when None).

    Returns
    -------
    list of tuple (int, str, str)
        ``(line, construct, explanation)``, one per construct found, the line counted from 1 and
        the explanation saying what pymoca does and what to write instead; empty when none.
    """
    spans = class_spans(code)
    hits = []
    for what, (pattern, does, instead) in MISREAD.items():
        for m in re.finditer(pattern, code):
            if not _skip(what, code, m, spans, loaded):
                start = m.start() + len(m.group()) - len(m.group().lstrip(";\n \t"))
                where = f" ({loaded})" if what == "final outside the loaded class" and loaded else ""
                hits.append((code.count("\n", 0, start) + 1, what, f"{does}; instead, {instead}{where}"))
                break
    return hits
