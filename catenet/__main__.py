"""``python -m catenet``: the command line, as the ``catenet`` script."""

from catenet.cli import main

if __name__ == "__main__":
    main(prog_name="catenet")
