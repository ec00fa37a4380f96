"""Drawing the collective gathering world with pygame; GIF/MP4, film strips, sensor layouts.

The picture follows the paper's Figure 3, seen from above (``docs/rendering.md`` shows every
option with a picture):

* the arena floor inside a dark wall band, and the gathering zone (``config.zone_rect``) in green;
* blocks as rotated squares coloured by size (small blue, medium amber, large red), never
  smaller than ``MIN_BLOCK_PX``; gathered blocks (``sim.gathered``) are darker with a white
  outline; blocks a robot is welded to (carried) have a magenta outline;
* robots as dark discs of at least ``min_robot_px`` pixels radius with a heading mark (a white
  line inside, a stub outside); robots welded to a block (``world.robot_attached >= 0``) are magenta; robots whose cones are
  shown while others' are not get an orange ring;
* sensor cones (circular sectors of radius ``range`` and full angle ``fov`` from the sensor's
  mount point on the rim, as in ``sensing.py``): all cones are drawn into ONE transparent layer
  (a light fill plus an outline per cone) that is composited once, so overlapping cones never
  darken each other however many there are. Cones are clipped at the walls;
* optional trails: every robot's path over the last ``trail`` recorded steps;
* an information panel to the right: step, gathered value and blocks by type, a sparkline of
  the gathered value, the morphology as a table and a legend (text needs ``pygame.font``).

Render options (``Renderer(...)``, ``parallel_env(render_options={...})``,
``env.render(**options)``, ``gathering-replay --cones/--view/--size/--trail/--no-panel``):

``size_px``      side of the square arena view in pixels (64..4096); the panel adds width.
``cones``        ``"auto"`` (default), ``"all"``, ``"none"`` or robot indices (``[3]``, ``"0,3"``).
                 ``"auto"`` is ``"all"`` while the team's summed cone area is at most
                 ``AUTO_CONES_COVER`` of the arena, otherwise the cones of one robot (the followed
                 robot in a follow view, else robot 0).
``view``         ``"full"`` (the arena), ``"zone"`` (a square crop around the zone) or
                 ``"follow:K"`` (``FOLLOW_SPAN`` units around robot K, which stays centred).
``trail``        K >= 0: draw each robot's path over its last K steps (0 = no trails). Positions
                 are kept while ``trail`` > 0 when the steps are recorded (``Renderer.record``).
``panel``        True: the information panel beside the arena.
``min_robot_px`` robots are drawn at least this many pixels in radius (>= 1).

Usage::

    env = parallel_env(render_mode="rgb_array", render_options={"view": "zone", "trail": 100})
    frame = env.render()                         # (640, 640 + panel, 3) uint8
    strip = film_strip([f0, f1, f2], ["step 0", "step 500", "step 1000"])
    save_png(sensor_layout(morphology), "sensors.png"); save_video(frames, "episode.gif")

World y points up (north); screen y points down. ``Renderer.to_screen`` maps world points to
frame pixels. pygame is imported lazily by ``Renderer`` so importing ``gathering_env`` does not
need it; ``"rgb_array"`` draws offscreen and never opens a window. The ``"human"`` window has
keys (listed in the window): space pause, right arrow step, +/- faster/slower, c cones, esc close.

Modules (every public name is re-exported here; import from ``gathering_env.render``):

``options``   ``RenderOptions``, ``RenderOptionError``, ``parse_cones``/``parse_view``, option bounds.
``renderer``  ``Renderer``: options, the view (world -> pixels), the recorded history, render/close.
``drawing``   colours, cone geometry, text and table helpers, the arena/trail/cone/block/robot layers.
``panel``     the information panel: counts, sparkline, morphology table, legend, ``KEYS``.
``window``    the ``"human"`` window: showing frames, the keys.
``figures``   ``film_strip``, ``sensor_layout``.
``export``    ``save_png``, ``save_video``, ``VideoWriter`` (frames streamed to the file).
"""

from .drawing import (
    BLOCK_COLOURS,
    CONE_EDGE_ALPHA,
    CONE_FILL_ALPHA,
    FLOOR,
    FOCUS,
    GATHERED_EDGE,
    GATHERED_SHADE,
    HEADING,
    MIN_BLOCK_PX,
    MUTED,
    PAGE,
    RGB,
    ROBOT,
    ROBOT_ATTACHED,
    SENSOR_COLOURS,
    TEXT,
    TRAIL,
    WALL,
    ZONE,
    ZONE_EDGE,
    cone_colour_on,
    cone_sensors,
    morphology_rows,
    team_cone_cover,
)
from .export import VideoWriter, save_png, save_video
from .figures import film_strip, sensor_layout
from .options import (
    AUTO_CONES_COVER,
    CONE_CHOICES,
    DEFAULT_MIN_ROBOT_PX,
    DEFAULT_SIZE_PX,
    FOLLOW_SPAN,
    VIEWS,
    ZONE_MARGIN,
    RenderOptionError,
    RenderOptions,
    parse_cones,
    parse_view,
)
from .panel import KEYS
from .renderer import Renderer

__all__ = [
    "RGB",
    "PAGE",
    "FLOOR",
    "WALL",
    "ZONE",
    "ZONE_EDGE",
    "BLOCK_COLOURS",
    "GATHERED_SHADE",
    "GATHERED_EDGE",
    "ROBOT",
    "ROBOT_ATTACHED",
    "HEADING",
    "FOCUS",
    "TRAIL",
    "TEXT",
    "MUTED",
    "SENSOR_COLOURS",
    "CONE_FILL_ALPHA",
    "CONE_EDGE_ALPHA",
    "DEFAULT_SIZE_PX",
    "DEFAULT_MIN_ROBOT_PX",
    "MIN_BLOCK_PX",
    "AUTO_CONES_COVER",
    "FOLLOW_SPAN",
    "ZONE_MARGIN",
    "VIEWS",
    "CONE_CHOICES",
    "KEYS",
    "RenderOptionError",
    "parse_cones",
    "parse_view",
    "RenderOptions",
    "cone_colour_on",
    "cone_sensors",
    "team_cone_cover",
    "morphology_rows",
    "Renderer",
    "film_strip",
    "sensor_layout",
    "save_png",
    "save_video",
    "VideoWriter",
]
