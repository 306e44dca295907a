"""`python3 -m board IMAGE ...`: runs IMAGE on the virtual board (board.py)."""

from .board import main

main(prog="python3 -m board")
