"""The client against the protocol's own list of commands: every command of
protocol/commands.inc has a Client method whose keyword arguments are exactly the fields its
reader in protocol/messages.cpp accepts. A command added to the daemon fails this test until
the client has it.

NEPHELE_SOURCE_DIR names the repository (default: three folders above this file)."""
import inspect
import os
import re
import unittest
from pathlib import Path

import nephele

SOURCE = Path(os.environ.get("NEPHELE_SOURCE_DIR", Path(__file__).resolve().parents[3]))


def protocol_commands() -> dict[str, str]:
    """The commands of protocol/commands.inc: wire name -> type name."""
    text = (SOURCE / "protocol" / "commands.inc").read_text()
    return dict(re.findall(r"^NEPHELE_COMMAND\((\w+), (\w+)\)", text, re.MULTILINE))


def protocol_fields(type_name: str) -> set[str]:
    """The fields read by `read<type_name>` in protocol/messages.cpp, from its `finish` list of
    allowed keys (`readNamed`: name; `readBare`: none), less cmd and id."""
    text = (SOURCE / "protocol" / "messages.cpp").read_text()
    reader = re.search(rf"^{type_name} read{type_name}\(FieldReader& r\) {{\n(.*?)^}}", text,
                       re.MULTILINE | re.DOTALL)
    if reader is None:
        raise AssertionError(f"no read{type_name} in protocol/messages.cpp")
    body = reader.group(1)
    if f"readNamed<{type_name}>" in body:
        return {"name"}
    if f"readBare<{type_name}>" in body:
        return set()
    finish = re.search(r'r\.finish\(\s*((?:"[^"]*"\s*)+)\)', body)
    if finish is None:
        raise AssertionError(f"read{type_name} names no allowed keys with r.finish")
    allowed = "".join(re.findall(r'"([^"]*)"', finish.group(1)))
    return {key.strip() for key in allowed.split(",")} - {"cmd", "id"}


class CommandsTest(unittest.TestCase):
    def test_every_command_has_a_method(self) -> None:
        commands = protocol_commands()
        self.assertIn("render", commands)  # the list was read
        missing = [name for name in commands if not callable(getattr(nephele.Client, name, None))]
        self.assertEqual(missing, [], "commands of protocol/commands.inc without a Client "
                                      "method in clients/python/nephele/client.py")

    def test_every_method_takes_the_fields_of_its_command(self) -> None:
        for name, type_name in protocol_commands().items():
            method = getattr(nephele.Client, name, None)
            if method is None:
                continue  # reported by test_every_command_has_a_method
            with self.subTest(command=name):
                parameters = set(inspect.signature(method).parameters) - {"self"}
                self.assertEqual(parameters, protocol_fields(type_name))


if __name__ == "__main__":
    unittest.main()
