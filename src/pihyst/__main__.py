import sys

from pihyst.cli import main

sys.exit(main())
