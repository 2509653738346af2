import sys

from layered_swim.cli import main

sys.exit(main())
