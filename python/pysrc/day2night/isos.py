"""The noisy ISO pair the paper's experiments use, spelled once for the whole package.

The release renders each noisy test input at these two ISOs (docs/experiment.md); every
module that needs the pair imports ``NOISY_ISOS`` from here.
"""

NOISY_ISOS = (1600, 3200)
