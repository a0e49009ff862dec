"""tribopipe: from raw rheometer pin-on-disc exports to a growing friction map.

Importing the package is cheap: no numpy, pandas, scipy or matplotlib at import time.
"""

__version__ = "0.1.0"
