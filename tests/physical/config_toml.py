"""A configuration dict written back as TOML, for the tests that hand one to the command line."""

import json


def config_toml(config: dict) -> str:
    """A configuration of sections of plain values, and the parts' tables (``[parts.<name>]``), as
    TOML."""
    lines = [f"name = {json.dumps(config['name'])}"]
    for section, values in config.items():
        if section == "parts":
            for name, table in values.items():
                lines += [f"[parts.{name}]", *(f"{k} = {json.dumps(v)}" for k, v in table.items())]
        elif isinstance(values, dict):
            lines += [f"[{section}]", *(f"{k} = {json.dumps(v)}" for k, v in values.items())]
    return "\n".join(lines) + "\n"
