"""Helpers shared by the figure scripts: colloidsim's CSV tables as columns, and one option
taken out of an argument list."""

import csv


def columns(path):
    """A CSV table with a header row as {name: [float, ...]}."""
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def option(args, name, default):
    """The value after `name` in `args` (both removed from the list), or `default`."""
    if name in args:
        i = args.index(name)
        value = args[i + 1]
        del args[i : i + 2]
        return value
    return default
