"""The exceptions a client raises: the daemon's error replies, and waits that ran out."""


class NepheleError(Exception):
    """An error reply from the daemon (PROTOCOL.md, "Errors").

    `code` is one of the protocol's codes (`bad_json`, `bad_field`, `unknown_command`,
    `too_large`, `unauthorized`, `busy`, `not_found`, `limit`, `failed`) and `message` the
    daemon's text, which names the field and what is allowed. After an error reply the
    connection stays usable and nothing has changed on the daemon.
    """

    def __init__(self, code: str, message: str) -> None:
        super().__init__(f"{code}: {message}")
        self.code = code
        self.message = message


class RequestTimeout(TimeoutError):
    """A reply or a subscribed frame did not arrive within the client's `timeout`.

    The client closes its connection when this is raised, since the late reply may still come
    and would be taken for another's; `Client.reconnect()` opens a new one.
    """
