"""The layout of a composition step's state and output: shared by the composer and its kernels.

One row of floats: the object's, the left palm's and the right palm's state values (19 each,
:data:`skills.state.STATE_SIZE`), their three phases, then the commands (palm positions
2 x 3, orientations 2 x 4, twists 2 x 6, object twist 6).
"""

from skills.state import STATE_SIZE

#: Where the three phases start.
PHASES = 3 * STATE_SIZE
#: Where the commands start.
COMMANDS = PHASES + 3
#: The length of a row.
ROW_SIZE = COMMANDS + 32
#: The interpreter's spaces: the object, then each palm in the object frame.
OBJECT, LEFT, RIGHT = 0, 1, 2
