"""``hand``: describe a hand, list the shipped hands, write its URDF, its strength."""

from __future__ import annotations

import argparse
import json
import sys


def add_parser(sub) -> None:
    h = sub.add_parser("hand", help="describe a hand, list hands, write its URDF")
    h.add_argument("--hand", default="default", help="hand name or hand file (.toml)")
    h.add_argument("--list", action="store_true", help="list the shipped hands")
    h.add_argument("--hands", metavar="LEFT,RIGHT",
                   help="two hands, the left one first: with --urdf, the pair's URDF (every "
                        "name prefixed left. or right.: docs/user/two-hands.md)")
    h.add_argument("--urdf", metavar="PATH", help="write the hand's URDF here ('-' for stdout)")
    h.add_argument("--strength", action="store_true",
                   help="the hand's strength from its model beside the seed's requirements")
    h.add_argument("--json", action="store_true", help="one JSON object on stdout")


def _list(as_json: bool) -> int:
    from planner.hand.builders import load_hand_spec
    from planner.hand.spec import list_hands

    hands = {n: load_hand_spec(n).description for n in list_hands()}
    if as_json:
        print(json.dumps({"command": "hand", "hands": [
            {"name": n, "description": d} for n, d in hands.items()]}))
    else:
        width = max(map(len, hands))
        for n, d in hands.items():
            print(f"{n:{width}s} {d}")
    return 0


def _urdf(hand, path: str, as_json: bool) -> int:
    if path == "-":
        sys.stdout.write(hand.urdf)
    else:
        from planner.output import write_file

        write_file(path, hand.urdf)
    if as_json:
        print(json.dumps({"command": "hand", "name": hand.name, "urdf": path,
                          "urdf_sha256": hand.urdf_sha256}))
    return 0


def _pair_urdf(names: str, path: str | None, as_json: bool) -> int:
    """``--hands LEFT,RIGHT --urdf PATH``: the two hands' URDF as one robot."""
    from planner.errors import InputError
    from planner.hand.model import load_hand
    from planner.hand.pair import pair_name, pair_urdf_text
    from planner.hand.urdf import urdf_sha256

    if path is None:
        raise InputError("--hands writes the pair's URDF: give --urdf PATH")
    hands = tuple(load_hand(n.strip()) for n in names.split(","))
    text = pair_urdf_text(hands)
    if path == "-":
        sys.stdout.write(text)
    else:
        from planner.output import write_file

        write_file(path, text)
    if as_json:
        print(json.dumps({"command": "hand", "name": pair_name(hands), "urdf": path,
                          "urdf_sha256": urdf_sha256(text)}))
    return 0


def run(a: argparse.Namespace) -> int:
    if a.strength and (a.list or a.urdf or a.hands):
        from planner.errors import InputError

        raise InputError("--strength cannot be combined with --list or --urdf"
                         + (" (nor with --hands)" if a.hands else ""))
    if a.list:
        return _list(a.json)
    if a.hands is not None:
        return _pair_urdf(a.hands, a.urdf, a.json)
    from planner.hand.describe import format_hand, hand_dict
    from planner.hand.model import load_hand

    hand = load_hand(a.hand)
    if a.urdf:
        return _urdf(hand, a.urdf, a.json)
    if a.strength:
        from planner.hand.strength import hand_strength

        st = hand_strength(hand)
        print(json.dumps(st.to_dict()) if a.json else st.summary())
        return 0
    print(json.dumps(hand_dict(hand)) if a.json else format_hand(hand))
    return 0
