#!/usr/bin/env python3
"""Writes the bench's hard lighting cases (issue 12) into tests/scenes/:

doorway.gltf  two 4 x 3 x 4 m rooms side by side along x, joined by a 1 x 2 m
              doorway in a 10 cm wall; one point light in room A (x < 0), hidden
              from the doorway by a partition, so room B gets no direct light:
              only what room A's walls reflect through the doorway. Probes: 8 x 2 x 4 at 1 m
              (bench/paths_to_error.c), half of them in the dark room.
panel.gltf    one 4 x 3 x 4 m room lit only by a 25 x 25 cm emissive ceiling
              panel of radiance 400, with a 1.2 x 1.2 m slab 1 m below it
              that shadows the floor and the probes under it, and a standing
              screen. Probes 4 x 3 x 4 at 1 m; the top row sees the panel.

lamps.gltf    the doorway's rooms without the partition, lit by three 30 cm
              emissive ceiling panels (two in room A, a dim one in room B):
              light selection among emitters mostly hidden from each other.

skylight.gltf one closed 4 x 3 x 4 m white room whose only light is a sun
              outside, coming in through a 1.2 x 1.2 m skylight of red thin
              glass (KHR_materials_transmission): every light path inside
              has passed the glass, so the room is lit red.

All are closed, single-sided and Lambertian (the skylight's glass aside),
so every light path stays inside. Only the Python standard library is used.
Run: python3 scripts/make_hard_scenes.py
"""
import os

from gltf_scene import Scene, material, scenes_dir

H = 3.0  # room height


def room(s, mesh, mat, x0, x1, z0, z1, door_side=None, door=None):
    """A room x0..x1, 0..H, z0..z1 whose faces look inward; the wall at
    x = door_side (x0 or x1) has a hole door = (z_lo, z_hi, top)."""
    q = s.quad
    s.add(mesh, mat, lambda: q((x0, 0, z1), (x1, 0, z1), (x1, 0, z0), (x0, 0, z0), (0, 1, 0)))     # floor
    s.add(mesh, mat, lambda: q((x0, H, z0), (x1, H, z0), (x1, H, z1), (x0, H, z1), (0, -1, 0)))    # ceiling
    s.add(mesh, mat, lambda: q((x0, 0, z0), (x1, 0, z0), (x1, H, z0), (x0, H, z0), (0, 0, 1)))     # z0 wall
    s.add(mesh, mat, lambda: q((x1, 0, z1), (x0, 0, z1), (x0, H, z1), (x1, H, z1), (0, 0, -1)))    # z1 wall

    def xwall(x, nx, za, zb, ya, yb):  # part z in [za, zb], y in [ya, yb] of the wall at x, facing nx
        if nx > 0:
            q((x, ya, zb), (x, ya, za), (x, yb, za), (x, yb, zb), (1, 0, 0))
        else:
            q((x, ya, za), (x, ya, zb), (x, yb, zb), (x, yb, za), (-1, 0, 0))

    for x, nx in ((x0, 1), (x1, -1)):
        if x == door_side:
            zl, zh, top = door
            s.add(mesh, mat, lambda: (xwall(x, nx, z0, zl, 0, H), xwall(x, nx, zh, z1, 0, H),
                                      xwall(x, nx, zl, zh, top, H)))
        else:
            s.add(mesh, mat, lambda: xwall(x, nx, z0, z1, 0, H))


def two_rooms(s, mat):
    """Rooms A (x < 0) and B (x > 0), 4 x 3 x 4 m, on either side of a 10 cm
    wall with a 1 x 2 m doorway (z 0.5 .. 1.5): meshes "room A", "room B"
    and "passage"."""
    door = (0.5, 1.5, 2.0)  # z from, z to, height
    t = 0.05                # half the wall's thickness
    room(s, "room A", mat, -4.0 - t, -t, -2.0, 2.0, door_side=-t, door=door)
    room(s, "room B", mat, t, 4.0 + t, -2.0, 2.0, door_side=t, door=door)
    zl, zh, top = door
    q = s.quad
    # the passage through the wall: jambs, lintel, sill
    s.add("passage", mat, lambda: (q((-t, 0, zl), (t, 0, zl), (t, top, zl), (-t, top, zl), (0, 0, 1)),
                                   q((t, 0, zh), (-t, 0, zh), (-t, top, zh), (t, top, zh), (0, 0, -1)),
                                   q((-t, top, zl), (t, top, zl), (t, top, zh), (-t, top, zh), (0, -1, 0)),
                                   q((-t, 0, zh), (t, 0, zh), (t, 0, zl), (-t, 0, zl), (0, 1, 0))))


def doorway():
    s = Scene()
    WALL, FLOOR, BLUE = range(3)
    two_rooms(s, WALL)
    # a partition in room A hides the doorway from the lamp: room B gets no
    # direct light at all, only what room A's walls reflect through the door
    s.add("partition", WALL, lambda: s.box((-2.05, 0.0, 0.0), (-1.95, H, 2.0)))
    # a blue cabinet in the dark room, so its light is not all grey
    s.add("cabinet", BLUE, lambda: s.box((2.6, 0.0, -1.9), (3.9, 1.6, -1.2)))
    gltf = {
        "asset": {"version": "2.0", "generator": "probebake scripts/make_hard_scenes.py"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"name": "lamp", "type": "point", "color": [1.0, 0.95, 0.85], "intensity": 40.0}]}},
        "scene": 0,
        "scenes": [{"name": "doorway", "nodes": [0, 1, 2, 3, 4, 5]}],
        "nodes": [{"name": "room A", "mesh": s.mesh_index("room A")},
                  {"name": "room B", "mesh": s.mesh_index("room B")},
                  {"name": "passage", "mesh": s.mesh_index("passage")},
                  {"name": "cabinet", "mesh": s.mesh_index("cabinet")},
                  {"name": "partition", "mesh": s.mesh_index("partition")},
                  {"name": "lamp", "translation": [-3.0, 2.5, 1.0],
                   "extensions": {"KHR_lights_punctual": {"light": 0}}}],
        "meshes": None,
        "materials": [material("wall", [0.7, 0.7, 0.7]), material("floor", [0.5, 0.45, 0.4]),
                      material("blue", [0.15, 0.25, 0.6])],
    }
    # the floors use the floor material
    for mesh in ("room A", "room B"):
        first, count, _ = s.primitives[mesh][0]
        s.primitives[mesh][0] = (first, count, FLOOR)
    s.write(os.path.join(scenes_dir(), "doorway.gltf"), gltf)


def panel():
    s = Scene()
    WALL, LIGHT, SLAB = range(3)
    room(s, "room", WALL, -2.0, 2.0, -2.0, 2.0)
    h, r = H - 0.01, 0.125
    s.add("panel", LIGHT, lambda: s.quad((-r, h, -r), (r, h, -r), (r, h, r), (-r, h, r), (0, -1, 0)))
    s.add("slab", SLAB, lambda: s.box((-0.6, 1.95, -0.6), (0.6, 2.0, 0.6)))
    s.add("screen", SLAB, lambda: s.box((1.0, 0.0, -1.8), (1.05, 1.8, 0.2)))
    gltf = {
        "asset": {"version": "2.0", "generator": "probebake scripts/make_hard_scenes.py"},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"name": "panel", "nodes": [0, 1, 2, 3]}],
        "nodes": [{"name": "room", "mesh": s.mesh_index("room")},
                  {"name": "panel", "mesh": s.mesh_index("panel")},
                  {"name": "slab", "mesh": s.mesh_index("slab")},
                  {"name": "screen", "mesh": s.mesh_index("screen")}],
        "meshes": None,
        "materials": [material("wall", [0.7, 0.7, 0.7]),
                      material("panel", [0.0, 0.0, 0.0], emissiveFactor=[1.0, 0.9, 0.75],
                               extensions={"KHR_materials_emissive_strength": {"emissiveStrength": 400.0}}),
                      material("slab", [0.55, 0.5, 0.45])],
    }
    s.write(os.path.join(scenes_dir(), "panel.gltf"), gltf)


def lamps():
    """The doorway's two rooms without the partition, lit by three small
    emissive ceiling panels: two in room A, one dim one in room B's far
    corner. Many-emitter selection in miniature: from room B, room A's
    panels are mostly behind the wall."""
    s = Scene()
    WALL, LIGHT, DIM = range(3)
    two_rooms(s, WALL)
    q = s.quad
    h, r = H - 0.01, 0.15

    def lamp(cx, cz):
        return q((cx - r, h, cz - r), (cx + r, h, cz - r), (cx + r, h, cz + r), (cx - r, h, cz + r), (0, -1, 0))

    s.add("lamps A", LIGHT, lambda: (lamp(-3.4, -1.4), lamp(-0.8, 1.5)))
    s.add("lamp B", DIM, lambda: lamp(3.5, -1.5))
    gltf = {
        "asset": {"version": "2.0", "generator": "probebake scripts/make_hard_scenes.py"},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"name": "lamps", "nodes": [0, 1, 2, 3, 4]}],
        "nodes": [{"name": "room A", "mesh": s.mesh_index("room A")},
                  {"name": "room B", "mesh": s.mesh_index("room B")},
                  {"name": "passage", "mesh": s.mesh_index("passage")},
                  {"name": "lamps A", "mesh": s.mesh_index("lamps A")},
                  {"name": "lamp B", "mesh": s.mesh_index("lamp B")}],
        "meshes": None,
        "materials": [material("wall", [0.7, 0.7, 0.7]),
                      material("lamp", [0.0, 0.0, 0.0], emissiveFactor=[1.0, 0.9, 0.75],
                               extensions={"KHR_materials_emissive_strength": {"emissiveStrength": 100.0}}),
                      material("dim lamp", [0.0, 0.0, 0.0], emissiveFactor=[0.75, 0.85, 1.0],
                               extensions={"KHR_materials_emissive_strength": {"emissiveStrength": 10.0}})],
    }
    s.write(os.path.join(scenes_dir(), "lamps.gltf"), gltf)


def skylight():
    s = Scene()
    WALL, GLASS = range(2)
    q, x, r = s.quad, 2.0, 0.6
    s.add("room", WALL, lambda: (
        q((-x, 0, x), (x, 0, x), (x, 0, -x), (-x, 0, -x), (0, 1, 0)),         # floor
        q((-x, 0, -x), (x, 0, -x), (x, H, -x), (-x, H, -x), (0, 0, 1)),       # walls, facing in
        q((x, 0, x), (-x, 0, x), (-x, H, x), (x, H, x), (0, 0, -1)),
        q((-x, 0, x), (-x, 0, -x), (-x, H, -x), (-x, H, x), (1, 0, 0)),
        q((x, 0, -x), (x, 0, x), (x, H, x), (x, H, -x), (-1, 0, 0)),
        # the ceiling around the skylight's opening, facing down
        q((-x, H, -x), (x, H, -x), (x, H, -r), (-x, H, -r), (0, -1, 0)),
        q((-x, H, r), (x, H, r), (x, H, x), (-x, H, x), (0, -1, 0)),
        q((-x, H, -r), (-r, H, -r), (-r, H, r), (-x, H, r), (0, -1, 0)),
        q((r, H, -r), (x, H, -r), (x, H, r), (r, H, r), (0, -1, 0))))
    s.add("skylight", GLASS, lambda: q((-r, H, -r), (r, H, -r), (r, H, r), (-r, H, r), (0, -1, 0)))
    gltf = {
        "asset": {"version": "2.0", "generator": "probebake scripts/make_hard_scenes.py"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_transmission"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"name": "sun", "type": "directional", "color": [1.0, 0.97, 0.9], "intensity": 20.0}]}},
        "scene": 0,
        "scenes": [{"name": "skylight", "nodes": [0, 1, 2]}],
        "nodes": [{"name": "room", "mesh": s.mesh_index("room")},
                  {"name": "skylight", "mesh": s.mesh_index("skylight")},
                  # pointing down (-Z turned to -Y), leaning 20 degrees toward +x
                  {"name": "sun", "rotation": [-0.69636424, -0.12278780, 0.12278780, 0.69636424],
                   "extensions": {"KHR_lights_punctual": {"light": 0}}}],
        "meshes": None,
        "materials": [material("wall", [0.8, 0.8, 0.8]),
                      material("red glass", [0.9, 0.2, 0.1], doubleSided=True,
                               extensions={"KHR_materials_transmission": {"transmissionFactor": 1.0}})],
    }
    s.write(os.path.join(scenes_dir(), "skylight.gltf"), gltf)


doorway()
panel()
lamps()
skylight()
