"""Each stateless predicate, true and false, on exact synthetic states."""

import math

import pytest
from eval_synth import TABLE_Z, obj, quat_axis, resting, scene, holds


@pytest.mark.parametrize("deg,expected", [(0, True), (25, True), (45, False)])
def test_upright(deg, expected):
    s = scene({"bottle": resting("bottle", quat=quat_axis("x", deg))})
    assert holds({"upright": {"object": "bottle", "max_tilt_deg": 30}}, s) is expected


def test_upright_custom_up_axis():
    lying = scene({"banana": resting("banana", quat=quat_axis("y", -90))})  # local x points up
    assert holds({"upright": {"object": "banana", "up_axis": [1, 0, 0], "max_tilt_deg": 5}}, lying)
    assert not holds({"upright": {"object": "banana", "max_tilt_deg": 5}}, lying)


def test_aligned():
    spec = {"aligned": {"object": "keyboard", "axis": [1, 0, 0], "direction": [1, 0, 0], "max_angle_deg": 10}}
    assert holds(spec, scene({"keyboard": resting("keyboard", quat=quat_axis("z", 8))}))
    assert not holds(spec, scene({"keyboard": resting("keyboard", quat=quat_axis("z", 30))}))


def test_inside_uses_cavity_box_in_container_frame():
    spec = {"inside": {"object": "apple", "container": "box"}}
    box = resting("box", 0.2, 0.1)  # centre z = 0.81, cavity centre z = 0.82
    assert holds(spec, scene({"box": box, "apple": obj([0.32, 0.1, 0.80])}))  # local x 0.12 < 0.13
    assert not holds(spec, scene({"box": box, "apple": obj([0.34, 0.1, 0.80])}))  # 0.14 > 0.13
    assert not holds(spec, scene({"box": box, "apple": obj([0.2, 0.1, 0.90])}))  # above the cavity
    spec_margin = {"inside": {"object": "apple", "container": "box", "margin": 0.02}}
    assert holds(spec_margin, scene({"box": box, "apple": obj([0.34, 0.1, 0.80])}))
    per_axis = {"inside": {"object": "apple", "container": "box", "margin": [0, 0, 0.05]}}
    assert holds(per_axis, scene({"box": box, "apple": obj([0.2, 0.1, 0.90])}))
    turned = resting("box", 0.0, 0.0, quat=quat_axis("z", 90))  # long side along world y
    assert holds(spec, scene({"box": turned, "apple": obj([0.0, 0.12, 0.8])}))
    assert not holds(spec, scene({"box": turned, "apple": obj([0.12, 0.0, 0.8])}))


def test_inside_explicit_box_for_a_shelf():
    upper = {"inside": {"object": "apple", "container": "fridge",
                        "box": {"offset": [0, 0, 0.3], "half_extents": [0.25, 0.25, 0.15]}}}
    fridge = obj([0, 0, 1.35])
    assert holds(upper, scene({"fridge": fridge, "apple": obj([0.1, 0, 1.7])}))
    assert not holds(upper, scene({"fridge": fridge, "apple": obj([0.1, 0, 1.2])}))


def test_on_surface_plate_and_table():
    plate = obj([0.0, 0.16, TABLE_Z + 0.008])
    top = TABLE_Z + 0.016
    spec = {"on_surface": {"object": "apple", "surface": "plate", "max_dist_xy": 0.15}}
    assert holds(spec, scene({"plate": plate, "apple": obj([0.05, 0.16, top + 0.04])}))
    assert not holds(spec, scene({"plate": plate, "apple": obj([0.20, 0.16, top + 0.04])}))  # 0.2 m off centre
    assert not holds(spec, scene({"plate": plate, "apple": obj([0.05, 0.16, top + 0.04 + 0.1])}))  # hovering
    footprint = {"on_surface": {"object": "apple", "surface": "plate"}}
    assert holds(footprint, scene({"plate": plate, "apple": obj([0.10, 0.16, top + 0.04])}))
    assert not holds(footprint, scene({"plate": plate, "apple": obj([0.12, 0.16, top + 0.04])}))
    on_table = {"on_surface": {"object": "apple", "surface": "table"}}
    assert holds(on_table, scene({"apple": resting("apple", 0.3, 0.3)}))
    assert not holds(on_table, scene({"apple": obj([0.3, 0.3, TABLE_Z + 0.2])}))


def test_on_surface_container_uses_cavity_floor():
    box = resting("box")  # centre 0.81, cavity floor 0.81 + 0.01 - 0.05 = 0.77
    spec = {"on_surface": {"object": "apple", "surface": "box"}}
    assert holds(spec, scene({"box": box, "apple": obj([0, 0, 0.77 + 0.04])}))
    assert not holds(spec, scene({"box": box, "apple": obj([0, 0, 0.77 + 0.04 + 0.05])}))


def test_within_distance_axes_offsets_and_points():
    s = scene({"apple": obj([0.3, 0.2, 0.80]), "plate": obj([0.3, 0.25, 0.76])})
    # offset (0, -0.05, 0.04): distance sqrt(0.05^2 + 0.04^2) = 0.064
    assert holds({"within_distance": {"object": "apple", "target": "plate", "max_dist": 0.065}}, s)
    assert not holds({"within_distance": {"object": "apple", "target": "plate", "max_dist": 0.06}}, s)
    assert holds({"within_distance": {"object": "apple", "target": "plate", "max_dist": 0.051, "axes": "xy"}}, s)
    assert not holds({"within_distance": {"object": "apple", "target": "plate", "max_dist": 0.049, "axes": "xy"}}, s)
    assert holds({"within_distance": {"object": "apple", "target": "plate", "max_dist": 0.041, "axes": "z"}}, s)
    assert holds({"within_distance": {"object": "apple", "target": "plate", "max_dist": 1e-9,
                                      "offset": [0, -0.05, 0.04]}}, s)
    assert holds({"within_distance": {"object": "apple", "target": "seat_a", "max_dist": 0.05}}, s)
    # "spot" is table-relative: z 0.10 above the tabletop, i.e. world z 0.85
    at_spot = scene({"apple": obj([0.0, 0.0, 0.85])})
    assert holds({"within_distance": {"object": "apple", "target": "spot", "max_dist": 1e-9}}, at_spot)
    higher_table = scene({"apple": obj([0.0, 0.0, 0.85])}, table=0.80)
    assert not holds({"within_distance": {"object": "apple", "target": "spot", "max_dist": 0.01}}, higher_table)


def test_matched_within_distance_is_one_to_one():
    spec = {"matched_within_distance": {"objects": ["glass_1", "glass_2"], "targets": ["seat_a", "seat_b"],
                                        "max_dist": 0.10, "axes": "xy"}}
    swapped = scene({"glass_1": obj([-0.3, 0.25, 0.83]), "glass_2": obj([0.32, 0.2, 0.83])})
    assert holds(spec, swapped)
    both_at_a = scene({"glass_1": obj([0.3, 0.25, 0.83]), "glass_2": obj([0.32, 0.2, 0.83])})
    assert not holds(spec, both_at_a)


def test_in_zone_rectangle_and_disc():
    assert holds({"in_zone": {"object": "box", "zone": "center"}}, scene({"box": resting("box", 0.05, -0.1)}))
    assert not holds({"in_zone": {"object": "box", "zone": "center"}}, scene({"box": resting("box", 0.15, 0)}))
    assert holds({"in_zone": {"object": "box", "zone": "serve"}}, scene({"box": resting("box", 0.43, -0.16)}))
    assert not holds({"in_zone": {"object": "box", "zone": "serve"}}, scene({"box": resting("box", 0.5, -0.2)}))


def test_relative_offset_world_and_reference_frame():
    left = {"relative_offset": {"object": "mouse", "reference": "keyboard", "axis": "y", "min": 0.15}}
    kb = resting("keyboard")
    assert holds(left, scene({"keyboard": kb, "mouse": resting("mouse", 0.0, 0.2)}))
    assert not holds(left, scene({"keyboard": kb, "mouse": resting("mouse", 0.3, 0.0)}))
    local = {"relative_offset": {"object": "mouse", "reference": "keyboard", "axis": "x", "min": 0.15,
                                 "max": 0.25, "frame": "reference"}}
    turned = resting("keyboard", quat=quat_axis("z", 90))  # keyboard x axis is world +y
    assert holds(local, scene({"keyboard": turned, "mouse": resting("mouse", 0.0, 0.2)}))
    assert not holds(local, scene({"keyboard": turned, "mouse": resting("mouse", 0.2, 0.0)}))


def test_at_rest():
    spec = {"at_rest": {"objects": ["apple", "banana"]}}
    assert holds(spec, scene({"apple": resting("apple", v=(0.01, 0, 0)), "banana": resting("banana")}))
    assert not holds(spec, scene({"apple": resting("apple", v=(0.1, 0, 0)), "banana": resting("banana")}))
    assert not holds(spec, scene({"apple": resting("apple"), "banana": resting("banana", w=(0, 0, 1.0))}))
    slow = scene({"apple": resting("apple", v=(0.1, 0, 0))})
    assert holds({"at_rest": {"objects": ["apple"], "max_lin_vel": 0.2}}, slow)


def test_lifted_and_moved_against_initial_state():
    start = scene({"apple": resting("apple")})
    up = scene({"apple": obj([0.0, 0.0, TABLE_Z + 0.04 + 0.06])})
    assert holds({"lifted": {"object": "apple", "min_height": 0.05}}, up, initial=start)
    assert not holds({"lifted": {"object": "apple", "min_height": 0.07}}, up, initial=start)
    slid = scene({"apple": resting("apple", 0.03, 0.04)})
    assert holds({"moved": {"object": "apple", "min_dist": 0.05}}, slid, initial=start)
    assert not holds({"moved": {"object": "apple", "min_dist": 0.051}}, slid, initial=start)


def test_held_and_held_near():
    air = obj([0.3, 0.0, TABLE_Z + 0.2])
    by_contact = scene({"bottle": air}, contacts=[("bottle", "right_hand")])
    assert holds({"held": {"object": "bottle"}}, by_contact)
    assert holds({"held": {"object": "bottle", "hand": "right"}}, by_contact)
    assert not holds({"held": {"object": "bottle", "hand": "left"}}, by_contact)
    by_palm = scene({"bottle": air}, hands={"left": [0.3, 0.05, TABLE_Z + 0.25], "right": [1, 1, 1]})
    assert holds({"held": {"object": "bottle", "hand": "left"}}, by_palm)
    on_table = scene({"bottle": resting("bottle", 0.3, 0.0)}, contacts=[("bottle", "right_hand")])
    assert not holds({"held": {"object": "bottle"}}, on_table)

    near = {"held_near": {"object": "bottle", "target": "seat_a", "max_dist": 0.25}}
    free = scene({"bottle": air})  # lifted, no hand near: only the hand-less form holds
    assert holds(near, free)
    assert not holds({"held_near": {**near["held_near"], "hand": "any"}}, free)
    assert holds({"held_near": {**near["held_near"], "hand": "right"}}, by_contact)
    assert not holds(near, on_table)
    assert not holds({"held_near": {**near["held_near"], "max_dist": 0.1}}, free)


def test_in_contact():
    s = scene({"apple": resting("apple")}, contacts=[("apple", "table"), ("apple", "left_hand")])
    assert holds({"in_contact": {"object": "apple", "other": "table"}}, s)
    assert holds({"in_contact": {"object": "apple", "other": "any_hand"}}, s)
    assert not holds({"in_contact": {"object": "apple", "other": "right_hand"}}, s)


def test_tilted_over_mouth_above_target():
    # bottle 0.1 m half height, rotated 60 deg about x: mouth at pos + 0.1 * (0, -sin60, cos60)
    pos = [0.0, 0.0, 1.0]
    mouth_y = -0.1 * math.sin(math.radians(60))
    tilted = scene({"bottle": obj(pos, quat_axis("x", 60)), "plate": obj([0.0, mouth_y - 0.03, 0.76])})
    spec = {"tilted_over": {"object": "bottle", "target": "plate", "radius": 0.05, "min_tilt_deg": 50}}
    assert holds(spec, tilted)
    assert not holds({"tilted_over": {**spec["tilted_over"], "radius": 0.02}}, tilted)
    barely = scene({"bottle": obj(pos, quat_axis("x", 40)), "plate": obj([0.0, mouth_y, 0.76])})
    assert not holds(spec, barely)
    far = scene({"bottle": obj(pos, quat_axis("x", 60)), "plate": obj([0.0, 0.2, 0.76])})
    assert not holds(spec, far)


def test_joint_predicates():
    s = scene(joints={"fridge/door": 1.2, "piano/C4": -0.03})
    assert holds({"joint_open": {"joint": "fridge/door", "threshold": 1.0}}, s)
    assert not holds({"joint_closed": {"joint": "fridge/door", "threshold": 0.1}}, s)
    assert holds({"joint_closed": {"joint": "fridge/door", "threshold": 1.3}}, s)
    assert holds({"joint_open": {"joint": "piano/C4", "threshold": -0.02, "direction": "negative"}}, s)
    assert not holds({"joint_closed": {"joint": "piano/C4", "threshold": -0.02, "direction": "negative"}}, s)
    assert holds({"joint_in_range": {"joint": "fridge/door", "min": 1.1, "max": 1.3}}, s)
    assert not holds({"joint_in_range": {"joint": "fridge/door", "min": 0.0, "max": 1.1}}, s)


def test_combinators():
    s = scene({"apple": resting("apple")})
    up = {"upright": {"object": "apple"}}
    high = {"lifted": {"object": "apple", "min_height": 0.5}}
    assert holds({"all": [up, {"not": high}]}, s)
    assert holds({"any": [high, up]}, s)
    assert not holds({"all": [up, high]}, s)
    assert not holds({"any": [{"not": up}, high]}, s)
