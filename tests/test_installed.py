"""The tests test what ``pip install`` put on disk: the imported gtmodel is the installed distribution's.

Independent check: the distribution's own record (``direct_url.json``, PEP 610) says where pip
installed it from and whether editable; the imported module must come from there, so a
non-editable install is tested from site-packages, never from the checkout beside the tests.
"""

from __future__ import annotations

import json
import sysconfig
from importlib import metadata
from pathlib import Path
from urllib.parse import unquote, urlparse

import gtmodel


SITE = Path(sysconfig.get_paths()["purelib"])


def _installed_from() -> tuple[bool, Path | None]:
    # the distribution pip installed into this environment (not an egg-info a build left in the checkout)
    (dist,) = [d for d in metadata.distributions(path=[str(SITE)]) if d.metadata["Name"] == "gtmodel"]
    text = dist.read_text("direct_url.json")
    info = json.loads(text) if text else {}
    editable = bool(info.get("dir_info", {}).get("editable", False))
    url = info.get("url", "")
    return editable, Path(unquote(urlparse(url).path)) if url.startswith("file:") else None


def test_the_imported_gtmodel_is_the_installed_one():
    editable, source = _installed_from()
    here = Path(gtmodel.__file__).resolve()
    if editable:
        assert source is not None and here.is_relative_to(source.resolve()), (here, source)
    else:
        assert here.parent == (SITE / "gtmodel").resolve(), f"gtmodel imported from {here.parent}, installed in {SITE}"
