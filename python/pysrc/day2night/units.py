"""``group_units``: the units of ``dataset_units`` grouped by input, one scheduler task each."""


def group_units(units):
    """The units (dicts from ``dataset_units``) grouped by input, in the order each input
    first appears: one list per input holding its variants. Give each group to one task
    calling ``write_units``, so that the input is read and decoded once for all of its
    variants, as ``day2night dataset`` does.

    >>> groups = group_units(day2night.dataset_units("day/", "night/", variants=3))
    >>> [len(g) for g in groups]
    [3, 3, 3]
    """
    groups = {}
    for u in units:
        groups.setdefault(u["path"], []).append(u)
    return list(groups.values())
