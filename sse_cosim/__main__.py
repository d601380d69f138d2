"""``python -m sse_cosim`` runs the command-line interface."""

from sse_cosim.cli.main import main

main()
