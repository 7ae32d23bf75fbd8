"""``python -m layershell``: the command line (:mod:`layershell.cli`)."""
from .cli import main

main()
