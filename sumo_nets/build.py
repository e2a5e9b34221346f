"""Rebuild the SUMO networks from their plain XML sources with the wheel's netconvert.

python sumo_nets/build.py            # every network
python sumo_nets/build.py highway    # one
"""

import sys

from ego.sumo.net import available_networks, build_network

if __name__ == "__main__":
    names = sys.argv[1:] or available_networks()
    for name in names:
        print(f"built {build_network(name)}")
