"""User-facing errors.

A :class:`CablelabError` is a problem with the user's input (a file, a key, a topic, a value).
The command line prints its message as one line and exits non-zero, without a traceback; every
message names the thing that is wrong and, where it can, says what to do.
"""


class CablelabError(Exception):
    """An error in the user's input, reported as one line naming the file, key, topic or value."""
