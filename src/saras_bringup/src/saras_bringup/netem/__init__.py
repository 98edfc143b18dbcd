"""User-space network impairment (delay, jitter, random and bursty loss, reordering) for UDP and
TCP links: impairment model, links-file parser and asyncio relay. ROS-free."""
from .config import LinkConfig, load_links, parse_links  # noqa: F401
from .impairment import Impairment, ImpairmentConfig, LinkStats  # noqa: F401
from .relay import Relay, RelayThread  # noqa: F401
