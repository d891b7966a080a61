"""``python -m icub_pmp.demo``: run the demo (see icub_pmp.demo.scenario)."""

import sys

from icub_pmp.demo.scenario import main

sys.exit(main())
