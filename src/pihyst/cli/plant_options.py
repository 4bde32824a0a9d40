"""Options that choose and configure a simulated beam, shared by simulate and track."""

from pihyst.cli.errors import seed
from pihyst.sim import PLANT_NAMES, make_plant


def add_plant_options(p, seed_help):
    """Add --plant, --seed, --no-noise, --no-creep, --no-quantisation, --dynamics."""
    p.add_argument("--plant", choices=PLANT_NAMES, default="paper-beam",
                   help="simulated beam (default: paper-beam, calibrated to the paper)")
    p.add_argument("--seed", type=seed, default=0, metavar="N", help=seed_help)
    p.add_argument("--no-noise", action="store_true", help="no sensor noise")
    p.add_argument("--no-creep", action="store_true", help="no creep")
    p.add_argument("--no-quantisation", action="store_true",
                   help="no 10 mV supply quantisation")
    p.add_argument("--dynamics", action="store_true",
                   help="add the beam's second-order dynamics (54 Hz resonance)")


def plant_from_options(args):
    """The simulated beam the options of :func:`add_plant_options` describe."""
    return make_plant(args.plant, seed=args.seed, noise=not args.no_noise,
                      creep=not args.no_creep, quantisation=not args.no_quantisation,
                      dynamics=args.dynamics)
