"""The interactive swimmer: ``python app.py --help`` for the options, H in the window for the keys."""
import sys

from layered_swim.app.main import main

if __name__ == "__main__":
    sys.exit(main())
