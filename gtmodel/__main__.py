"""``python -m gtmodel``: the ``gtmodel`` command (:func:`gtmodel.cli.main`)."""

from gtmodel.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
