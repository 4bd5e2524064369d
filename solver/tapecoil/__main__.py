import sys

from tapecoil.app.cli import main

sys.exit(main())
