"""``python -m evotol.cli``: the ``evotol`` command."""
from evotol.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
