"""Message definitions shared by every node (docs/architecture.md "Messages"). Import from here."""

from common.errors import SchemaError
from schemas.base import Message
from schemas.keys import Keys
from schemas.messages import *  # noqa: F403
from schemas.messages import __all__ as _messages_all

__all__ = ["Keys", "Message", "SchemaError", *_messages_all]
