import sys

from vxf_farm.submit import main

sys.exit(main())
