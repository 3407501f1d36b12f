#!/usr/bin/python3
"""Assembles glTF 2.0 interior scenes resembling the paper's five test scenes from freely licensed
Debian packages (docs/design.md §8): furniture from `sweethome3d-furniture` (CC0 / CC-BY 3.0 OBJ models) and
the bunny from `libcgal-demo`'s data.  Python 3 standard library only; nothing is downloaded.

Each scene is one .glb: one glTF mesh per object (OBJ triangle order kept, polygons fanned), one node
per instance (translation, rotation about y, scale to the catalog's width/height/depth in metres),
a baseColorFactor per material (the MTL's Kd, else grey), emissive ceiling quads as area lights and a
perspective camera in the room.  Beside it, <scene>.json records the models and the counts, and
CREDITS.md (rewritten on every run) lists every model of every scene in the folder.

Usage: assemble_real_scenes.py [--out DIR] [--force] SCENE... | --all
Exit status: 0 success, 1 a scene missed its target counts, 2 bad usage or missing input packages.
"""
import argparse
import array
import glob
import hashlib
import json
import math
import os
import re
import struct
import sys
import tarfile
import time
import zipfile

FURNITURE_DIR = "/usr/share/sweethome3d/furniture"
CGAL_DATA = ["/usr/share/doc/libcgal-dev/data.tar.gz", "/usr/share/doc/libcgal-demo/data.tar.gz"]

# The catalogs we may use, with the licence /usr/share/doc/sweethome3d-furniture/copyright gives them
# (all CC0 or CC-BY 3.0; every catalog of the package qualifies, but a new one must be checked first).
CATALOG_LICENSES = {
    "BlendSwap-CC-0": "CC0-1.0",
    "BlendSwap-CC-BY": "CC-BY-3.0",
    "KatorLegaz": "CC-BY-3.0-US (c) 2003-2008 Andrew Kator & Jennifer Legaz",
    "Reallusion": "CC-BY-3.0-US (c) 2008-2011 Reallusion",
    "Scopia": "CC-BY-3.0 (c) Emmanuel Puybaret / eTeks and Scopia Visual Interfaces Systems, s.l.",
}

GREY = (0.6, 0.6, 0.6)
MAX_ALBEDO = 0.9  # keeps every surface below perfect reflection, so indirect light converges

# ---------------------------------------------------------------------------------------------------
# The scenes.  Targets are the paper's Table 2 (objects = unique meshes = second-level BVHs; triangles
# in world space).  The models were picked once, offline, from the catalogs' theme categories: a few
# must-haves per room, then greedily the themed model closest to the triangles still missing per slot.
# Comments give the catalog's name, category and the model's triangles.  The 7 room objects (floor,
# ceiling, 4 walls, one light quad mesh) are added by the assembler.
# ---------------------------------------------------------------------------------------------------

SCENES = {
    # FIREPLACE-like: living room with a fireplace.
    "fireplace": {
        "title": "FIREPLACE-like", "objects": 49, "triangles": 143000,
        "furniture": [
            'Scopia#fireplace1',  # Fireplace, Living room, 752
            'Scopia#clear_sofa',  # Clear sofa, Living room, 6720
            'Blend Swap CC-0#armchair2',  # Armchair, Living room, 6666
            'Scopia#table_wood_and_iron',  # Coffee table, Living room, 3068
            'Kator Legaz#full-bookcase',  # Full bookcase, Living room, 2348
            'Blend Swap CC-0#littlePlant',  # Little plant, Living room, 2232
            'Scopia#living_lamp',  # Lamp, Lights, 4594
            'Scopia#tv',  # TV 16:9, Living room, 2732
            'Kator Legaz#oriental-rug',  # Oriental rug, Living room, 44
            'Blend Swap CC-0#pianoAQueue',  # Grand piano, Living room, 4832
            'Kator Legaz#mid-century-sofa',  # Sofa, Living room, 5244
            'Scopia#dining_room',  # Bookcase, Living room, 4960
            'Blend Swap CC-BY#childChair',  # Child chair, Living room, 3520
            'Blend Swap CC-BY#fotel',  # Armchair, Living room, 4896
            'Scopia#white_kitchen_chair',  # Chair, Living room, 4776
            'Kator Legaz#folding-table',  # Folding table, Living room, 4408
            'Scopia#chair',  # Chair, Living room, 1776
            'Kator Legaz#bar-stool',  # Bar stool, Living room, 4828
            'Blend Swap CC-BY#chair3',  # Chair, Living room, 1888
            'Scopia#armchair1',  # Armchair, Living room, 3976
            'Scopia#ryokanChair',  # Ryokan chair, Living room, 1564
            'Blend Swap CC-0#shelves',  # Shelves, Living room, 1840
            'Blend Swap CC-BY#cafe_set_mota_table',  # Round table, Living room, 4896
            'Blend Swap CC-0#tableWithTablecloth',  # Table with tablecloth, Living room, 1834
            'Blend Swap CC-0#verticalShelves',  # Vertical shelves, Living room, 1832
            'Scopia#dvd',  # DVD player, Living room, 3236
            'Scopia#ps4-joystick',  # Joystick, Living room, 2274
            'Scopia#metal_glass_table',  # Glass table, Living room, 3148
            'Blend Swap CC-0#oakTable',  # Oak table, Living room, 5160
            'Scopia#chair3',  # Chair, Living room, 2052
            'Blend Swap CC-BY#kitchenChair',  # Chair, Living room, 3900
            'Blend Swap CC-BY#bookcase',  # Bookcase, Living room, 3418
            'Blend Swap CC-0#sillaBlanca',  # Chair, Living room, 5400
            'Scopia#living_room_table',  # Table, Living room, 1610
            'Scopia#table3',  # Table, Living room, 4042
            'Scopia#aquarium',  # Aquarium, Living room, 5622
            'Blend Swap CC-0#table',  # Table, Living room, 1484
            'Blend Swap CC-0#chair2',  # Chair, Living room, 1912
            'Blend Swap CC-0#osakaChair',  # Osaka chair, Living room, 2430
            'Blend Swap CC-BY#plaidChair',  # Chair, Living room, 1872
            'Kator Legaz#mid-century-chair',  # Armchair, Living room, 8832
            'Blend Swap CC-BY#tvStand',  # TV stand, Living room, 368
        ],
    },
    # BREAKFAST-like: kitchen and dining table, small items laid on the tables.
    "breakfast": {
        "title": "BREAKFAST-like", "objects": 45, "triangles": 269000,
        "furniture": [
            'Blend Swap CC-0#tableWithTablecloth',  # Table with tablecloth, Living room, 1834
            'Blend Swap CC-0#oakTable',  # Oak table, Living room, 5160
            'Blend Swap CC-BY#kitchenChair',  # Chair, Living room, 3900
            'Scopia#white_kitchen_chair',  # Chair, Living room, 4776
            'Blend Swap CC-0#refrigerator',  # Refrigerator, Kitchen, 15356
            'Scopia#baby_high_chair',  # Baby high chair, Kitchen, 3948
            'Blend Swap CC-0#stool',  # Stool, Kitchen, 7050
            'Kator Legaz#propane-stove',  # Propane stove, Kitchen, 6012
            'Blend Swap CC-0#knifeStandSwap',  # Knife stand, Kitchen, 14608
            'Blend Swap CC-BY#breadBox',  # Bread box, Kitchen, 3788
            'Scopia#birthday_cake',  # Birthday cake, Kitchen, 8172
            'Blend Swap CC-0#coffeeBrewer',  # Coffee brewer, Kitchen, 13301
            'Blend Swap CC-BY#cocktailGlass',  # Cocktail glass, Kitchen, 7808
            'Blend Swap CC-0#hotDog',  # Hot dog, Kitchen, 6305
            'Scopia#frenchFries',  # French fries, Kitchen, 10800
            'Blend Swap CC-0#caffe_final',  # Coffee cup, Kitchen, 6838
            'Scopia#kitchen_tool3',  # Tool, Kitchen, 9504
            'Blend Swap CC-0#stove',  # Stove, Kitchen, 12228
            'Scopia#kitchen_tool4',  # Tool, Kitchen, 12448
            'Blend Swap CC-0#butter',  # Butter, Kitchen, 7584
            'Scopia#bar_chair',  # Bar chair, Kitchen, 3636
            'Blend Swap CC-0#beerGlass',  # Beer glass, Kitchen, 9836
            'Scopia#stoneGrillDevice',  # Stone grill device, Kitchen, 8420
            'Blend Swap CC-0#plasticCup',  # Plastic cup, Kitchen, 11260
            'Scopia#small-oven',  # Small oven, Kitchen, 2692
            'Blend Swap CC-0#tetrapak',  # Milk, Kitchen, 5068
            'Kator Legaz#plate-and-ustensils',  # Plate, glass and cutlery, Kitchen, 8672
            'Blend Swap CC-BY#utensilsPot',  # Utensils pot, Kitchen, 2748
            'Scopia#kitchen_tool2',  # Tool, Kitchen, 7392
            'Kator Legaz#bullet-trash-can',  # Bullet trash can, Kitchen, 2752
            'Scopia#coffee_machine',  # Coffee machine, Kitchen, 5534
            'Scopia#kitchenKnifeStandSet',  # Knife stand, Kitchen, 4912
            'Scopia#kitchen_tool1',  # Tool, Kitchen, 7392
            'Blend Swap CC-0#stool2',  # Stool, Kitchen, 2912
            'Scopia#sugar',  # Sugar, Kitchen, 11712
            'Blend Swap CC-BY#kitchenKnife',  # Kitchen knife, Kitchen, 2208
            'Blend Swap CC-BY#coffee_cup',  # Coffee cup, Kitchen, 5760
            'Blend Swap CC-BY#towel',  # Towel, Kitchen, 4564
        ],
    },
    # LIVING-ROOM-like: large living room.
    "livingroom": {
        "title": "LIVING-ROOM-like", "objects": 78, "triangles": 576000,
        "furniture": [
            'Scopia#fireplace2',  # Fireplace, Living room, 1588
            'Blend Swap CC-0#L_shaped_sofa',  # Corner sofa, Living room, 57968
            'Scopia#simple_sofa',  # Sofa, Living room, 9408
            'Blend Swap CC-0#plant',  # Plant, Living room, 14370
            'Blend Swap CC-0#chair',  # Chair, Living room, 9584
            'Scopia#burlap_sofa',  # Burlap sofa, Living room, 11920
            'Kator Legaz#mid-century-bench-sofa',  # Sofa, Living room, 12086
            'Scopia#plastic_chair',  # Plastic chair, Living room, 10352
            'Blend Swap CC-0#chairWithCushion',  # Chair with cushion, Living room, 12368
            'Blend Swap CC-BY#green_stool',  # Stool, Living room, 9856
            'Blend Swap CC-0#thonet',  # Chair, Living room, 9478
            'Blend Swap CC-BY#armchair1',  # Armchair, Living room, 8640
            'Kator Legaz#MIDI-keyboard',  # Keyboard, Living room, 7096
            'Blend Swap CC-0#antiqueChair',  # Chair, Living room, 9904
            'Blend Swap CC-0#designChair',  # Chair, Living room, 7446
            'Blend Swap CC-BY#cafe_set_tonon_chair',  # Chair, Living room, 11444
            'Scopia#modern_armchair',  # Modern armchair, Living room, 13344
            'Blend Swap CC-BY#cafe_set_tonon_table',  # Table, Living room, 3384
            'Scopia#armchair',  # Armchair, Living room, 5232
            'Blend Swap CC-0#deer',  # Deer, Living room, 6316
            'Kator Legaz#futon-couch',  # Futon couch, Living room, 5248
            'Blend Swap CC-BY#cafe_set_mota_chair',  # Chair, Living room, 6076
            'Scopia#maceta',  # Plant, Living room, 3496
            'Blend Swap CC-BY#ella_chair_f',  # Chair, Living room, 13346
            'Blend Swap CC-0#sofa2',  # Sofa, Living room, 10507
            'Blend Swap CC-BY#dresserWithDrawers',  # Dresser with drawers, Living room, 7356
            'Scopia#bonsai-tree',  # Bonsai tree, Living room, 8128
            'Scopia#complements2',  # Candle, Lights, 12630
            'Kator Legaz#chair-ottoman',  # Armchair ottoman, Living room, 3280
            'Blend Swap CC-BY#lamp',  # Lamp, Lights, 9792
            'Scopia#little_lamp1',  # Little lamp, Lights, 6858
            'Scopia#livingroom_lamp1',  # Lamp, Lights, 7384
            'Scopia#little_lamp3',  # Little lamp, Lights, 11758
            'Scopia#armchair3',  # Armchair, Living room, 3176
            'Kator Legaz#pedestal-vase-lamp',  # Pedestal vase lamp, Lights, 6228
            'Scopia#farola1',  # Street lamp, Lights, 11952
            'Blend Swap CC-BY#campingLamp',  # Camping lamp, Lights, 7490
            'Scopia#desk_lamp1',  # Desk lamp, Lights, 7192
            'Scopia#desk_lamp2',  # Desk lamp, Lights, 3724
            'Scopia#little_lamp2',  # Little lamp, Lights, 3486
            'Blend Swap CC-0#desklamp',  # Desk lamp, Lights, 3584
            'Blend Swap CC-0#fireExtinguisher',  # Extinguisher, Miscellaneous, 10868
            'Blend Swap CC-BY#mp3Station',  # MP3 station, Miscellaneous, 10272
            'Blend Swap CC-0#headphones',  # Headphones, Miscellaneous, 7640
            'Scopia#clothes-horse',  # Clothes horse, Miscellaneous, 4728
            'Blend Swap CC-0#speaker3',  # Speaker, Miscellaneous, 9924
            'Scopia#mower',  # Mower, Miscellaneous, 3718
            'Blend Swap CC-BY#suitcase',  # Suitcase, Miscellaneous, 6666
            'Blend Swap CC-BY#wire-coathanger',  # Wire coathanger, Miscellaneous, 4888
            'Scopia#glasses',  # Glasses, Miscellaneous, 10236
            'Scopia#candle',  # Candle, Lights, 2934
            'Blend Swap CC-BY#sunglasses',  # Sunglasses, Miscellaneous, 8268
            'Scopia#indoor-bike',  # Indoor bike, Miscellaneous, 4054
            'Blend Swap CC-BY#ballonFoot',  # Soccer ball, Miscellaneous, 8968
            'Blend Swap CC-0#speaker2',  # Speaker, Miscellaneous, 8874
            'Blend Swap CC-0#bookcase',  # Bookcase, Living room, 2858
            'Blend Swap CC-0#lockedLocker',  # Locked locker, Miscellaneous, 6816
            'Blend Swap CC-0#radiator2',  # Radiator, Miscellaneous, 6638
            'Scopia#electric_water_heater_big',  # Electric water heater, Miscellaneous, 4796
            'Scopia#punching-ball',  # Punching ball, Miscellaneous, 3064
            'Blend Swap CC-BY#mobile',  # Mobile phone, Miscellaneous, 11630
            'Kator Legaz#clothes-hanger',  # Clothes hanger, Miscellaneous, 2688
            'Blend Swap CC-0#desk',  # Desk, Office, 3013
            'Scopia#vase2',  # Vase, Miscellaneous, 11776
            'Blend Swap CC-0#ruler',  # Ruler, Office, 8772
            'Scopia#tubular_chair',  # Chair, Living room, 2560
            'Scopia#water_cooler',  # Water cooler, Office, 2510
            'Blend Swap CC-0#dustbin',  # Dustbin, Office, 3678
            'Blend Swap CC-BY#book',  # Book, Miscellaneous, 12320
            'Blend Swap CC-BY#tableTennisBat',  # Table tennis bat, Miscellaneous, 2120
            'Blend Swap CC-BY#officeTable',  # Desk, Office, 4190
        ],
    },
    # SALLE-DE-BAIN-like: bathroom fixtures, then dense plants and sofas (the catalogs hold too few dense
    # bathroom models for 1.2M triangles).
    "salledebain": {
        "title": "SALLE-DE-BAIN-like", "objects": 39, "triangles": 1231000,
        "furniture": [
            'Blend Swap CC-BY#bath_jay_hardy',  # Bath, Bathroom, 61308
            'Blend Swap CC-0#washbasin',  # Washbasin, Bathroom, 49034
            'Scopia#double_vanity',  # Double vanity, Bathroom, 30906
            'Blend Swap CC-BY#toilets_unit_jay_hardy',  # Toilets unit, Bathroom, 30470
            'Scopia#islandBath',  # Island bath, Bathroom, 23390
            'Blend Swap CC-0#showerStall',  # Shower stall, Bathroom, 21998
            'Scopia#corner_bathtub',  # Corner bathtub, Bathroom, 19267
            'Scopia#bathroom_vanity',  # Vanity, Bathroom, 19136
            'Blend Swap CC-BY#modernToilet',  # Toilets unit, Bathroom, 18640
            'Blend Swap CC-0#bidet',  # Bidet, Bathroom, 12034
            'Blend Swap CC-0#modernVanity',  # Vanity, Bathroom, 12001
            'Blend Swap CC-BY#washbasin_jay_hardy',  # Washbasin, Bathroom, 24624
            'Blend Swap CC-BY#foldingChair',  # Folding chair, Living room, 31272
            'Scopia#beige_sofa',  # Sofa 3 seats, Living room, 35496
            'Blend Swap CC-BY#sofa3',  # Sofa, Living room, 25200
            'Blend Swap CC-BY#tulip',  # Tulips, Living room, 72384
            'Kator Legaz#utility-shelving',  # Shelves, Living room, 26714
            'Scopia#ficus',  # Ficus, Living room, 43448
            'Blend Swap CC-0#electricGuitar',  # Electric guitar, Living room, 40348
            'Blend Swap CC-0#led_tv',  # TV, Living room, 29740
            'Blend Swap CC-BY#arbolito',  # Christmas tree, Living room, 26184
            'Blend Swap CC-0#oakChair',  # Oak chair, Living room, 31786
            'Blend Swap CC-0#televisionCabinet',  # Television cabinet, Living room, 30812
            'Blend Swap CC-BY#tulips',  # Tulips, Living room, 64288
            'Blend Swap CC-BY#mediumIndoorPlant',  # Indoor plant, Living room, 39470
            'Blend Swap CC-0#orchids',  # Orchids, Living room, 44830
            'Blend Swap CC-BY#spider_plant',  # Spider plant, Living room, 54080
            'Scopia#beige_sofa_2seats',  # Sofa 2 seats, Living room, 38598
            'Blend Swap CC-BY#spatifilum',  # Spathiphyllum, Living room, 128386
            'Blend Swap CC-BY#luckyBamboo',  # Bamboo, Living room, 37247
            'Blend Swap CC-0#decorativePlant',  # Decorative plant, Living room, 63428
            'Scopia#leather_sofa',  # Sofa, Living room, 26924
        ],
    },
    # BUNNY-like: 64 instances of the Stanford bunny (CGAL's 75,408-triangle bunny00.off; the paper's has
    # ~70k) on a rug in a room; 9 objects as in the paper's 2L-LS(0) count.
    "bunny": {
        "title": "BUNNY-like", "objects": 9, "instances": 72, "triangles": 4467000,
        "bunny": {"member": "data/meshes/bunny00.off", "grid": 8, "height": 0.35},
        "furniture": [
            'Kator Legaz#oriental-rug',  # Oriental rug, Living room, 44
        ],
    },
}


def bail(message, status=2):
    print("assemble_real_scenes: " + message, file=sys.stderr)
    sys.exit(status)


# ---- Java .properties (the catalogs' format) ----

def read_properties(text):
    """key=value pairs of a Java properties file: comments, continuation lines, \\uXXXX escapes."""
    out = {}
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i].lstrip()
        i += 1
        if not line or line[0] in "#!":
            continue
        while re.search(r"(?<!\\)(\\\\)*\\$", line) and i < len(lines):
            line = line[:-1] + lines[i].lstrip()
            i += 1
        m = re.match(r"((?:\\.|[^=:\s\\])*)\s*[=:\s]?\s*(.*)$", line)
        key, value = m.group(1), m.group(2)

        def unescape(s):
            s = re.sub(r"\\u([0-9a-fA-F]{4})", lambda u: chr(int(u.group(1), 16)), s)
            return re.sub(r"\\(.)", lambda e: {"t": "\t", "n": "\n", "r": "\r"}.get(e.group(1), e.group(1)), s)

        out[unescape(key)] = unescape(value)
    return out


class Catalog:
    """One .sh3f file: a zip holding OBJ/MTL models and PluginFurnitureCatalog.properties."""

    def __init__(self, path):
        self.path = path
        self.name = os.path.basename(path)[: -len(".sh3f")]
        self.license = CATALOG_LICENSES[self.name]
        self.zip = zipfile.ZipFile(path)
        props = read_properties(self.zip.read("PluginFurnitureCatalog.properties").decode("latin-1"))
        self.pieces = {}
        n = 1
        while "id#%d" % n in props:
            piece = {k[: -len("#%d" % n)]: v for k, v in props.items() if k.endswith("#%d" % n)}
            piece["catalog"] = self
            self.pieces[piece["id"]] = piece
            n += 1

    def read_text(self, member):
        return self.zip.read(member).decode("latin-1")

    def source_note(self, piece):
        """'Released under ... / Downloaded from URL' from a Blend Swap model's own licence file."""
        folder = os.path.dirname(piece["model"].lstrip("/"))
        try:
            text = self.read_text(folder + "/BLENDSWAP_LICENSE.txt")
        except KeyError:
            return None
        lines = [l.strip() for l in text.splitlines()]
        note = {}
        for k, l in enumerate(lines):
            if l.startswith("Thank you for downloading"):
                note["title"] = l[len("Thank you for downloading "):]
            if l == "Released under" and k + 1 < len(lines):
                note["license"] = lines[k + 1]
            if l.startswith("Downloaded from"):
                note["url"] = l.split()[-1]
        return note


def open_catalogs():
    catalogs = {}
    for path in sorted(glob.glob(os.path.join(FURNITURE_DIR, "*.sh3f"))):
        name = os.path.basename(path)[: -len(".sh3f")]
        if name in CATALOG_LICENSES:
            catalogs[name] = Catalog(path)
    if not catalogs:
        bail("no furniture catalogs in %s: install sweethome3d-furniture (scripts/assemble-scenes.sh does)" % FURNITURE_DIR)
    return catalogs


# ---- geometry ----

class Primitive:
    """Triangles of one material, with their own compact vertex arrays."""

    def __init__(self, material):
        self.material = material  # index into the scene's materials
        self.positions = array.array("f")
        self.normals = array.array("f")  # empty: the loader computes them
        self.indices = array.array("I")


class Mesh:
    def __init__(self, name):
        self.name = name
        self.primitives = []
        self.lo = [math.inf] * 3
        self.hi = [-math.inf] * 3

    def triangles(self):
        return sum(len(p.indices) // 3 for p in self.primitives)

    def grow_bounds(self):
        for p in self.primitives:
            for axis in range(3):
                values = p.positions[axis::3]
                if values:
                    self.lo[axis] = min(self.lo[axis], min(values))
                    self.hi[axis] = max(self.hi[axis], max(values))


class Materials:
    def __init__(self):
        self.items = []  # dicts: name, color, emission
        self.index = {}

    def add(self, name, color, emission=None):
        key = (name, tuple(color), tuple(emission or ()))
        if key not in self.index:
            self.index[key] = len(self.items)
            self.items.append({"name": name, "color": color, "emission": emission})
        return self.index[key]


def read_mtl(text):
    """material name -> Kd (r, g, b), for the materials that give one."""
    kd, current = {}, None
    for line in text.splitlines():
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "newmtl":
            current = line.split(None, 1)[1].strip() if len(parts) > 1 else ""
        elif parts[0] == "Kd" and current is not None and len(parts) >= 4:
            try:
                kd[current] = tuple(min(MAX_ALBEDO, max(0.0, float(v))) for v in parts[1:4])
            except ValueError:
                pass
    return kd


def obj_index(token, count):
    i = int(token)
    return i - 1 if i > 0 else count + i


def read_obj(catalog, piece, materials, rotation):
    """The OBJ of a catalog piece as a Mesh: faces fanned in file order, one primitive per run of
    faces with the same material (so triangle ids follow the file), the model rotation applied."""
    member = piece["model"].lstrip("/")
    folder = os.path.dirname(member)
    text = catalog.read_text(member)
    kd = {}
    for line in text.splitlines():
        if line.startswith("mtllib"):
            for lib in line.split(None, 1)[1].split():
                try:
                    kd.update(read_mtl(catalog.read_text(os.path.normpath(os.path.join(folder, lib)))))
                except KeyError:
                    pass
    v, vn = [], []
    mesh = Mesh(piece["id"])
    prim, prim_mtl, remap, has_normals = None, None, None, True
    current_mtl = ""

    def finish():
        if prim is not None and not has_normals:
            del prim.normals[:]

    for line in text.splitlines():
        if line.startswith("v "):
            x, y, z = (float(c) for c in line.split()[1:4])
            v.append((x, y, z))
        elif line.startswith("vn "):
            x, y, z = (float(c) for c in line.split()[1:4])
            vn.append((x, y, z))
        elif line.startswith("usemtl"):
            current_mtl = line[6:].strip()
        elif line.startswith("f "):
            if prim is None or prim_mtl != current_mtl:
                finish()
                color = kd.get(current_mtl, GREY)
                prim = Primitive(materials.add("%s/%s" % (piece["id"], current_mtl), color))
                prim_mtl, remap, has_normals = current_mtl, {}, True
                mesh.primitives.append(prim)
            corners = []
            for token in line.split()[1:]:
                fields = token.split("/")
                vi = obj_index(fields[0], len(v))
                ni = obj_index(fields[2], len(vn)) if len(fields) > 2 and fields[2] else None
                if ni is None:
                    has_normals = False
                key = (vi, ni)
                local = remap.get(key)
                if local is None:
                    local = remap[key] = len(prim.positions) // 3
                    prim.positions.extend(rotate(rotation, v[vi]))
                    prim.normals.extend(rotate(rotation, vn[ni]) if ni is not None else (0.0, 0.0, 0.0))
                corners.append(local)
            for k in range(1, len(corners) - 1):  # fan, as a convex polygon
                prim.indices.extend((corners[0], corners[k], corners[k + 1]))
    finish()
    mesh.primitives = [p for p in mesh.primitives if len(p.indices)]
    mesh.grow_bounds()
    return mesh


def rotate(m, p):
    if m is None:
        return p
    return (m[0] * p[0] + m[1] * p[1] + m[2] * p[2],
            m[3] * p[0] + m[4] * p[1] + m[5] * p[2],
            m[6] * p[0] + m[7] * p[1] + m[8] * p[2])


def read_off_from_tar(member_name, materials, color):
    """A triangle OFF mesh from CGAL's data archive, as one primitive."""
    for path in CGAL_DATA:
        if os.path.exists(path):
            with tarfile.open(path) as tar:
                text = tar.extractfile(member_name).read().decode("latin-1")
            break
    else:
        bail("no CGAL data archive (%s): install libcgal-demo (scripts/assemble-scenes.sh does)" % CGAL_DATA[0])
    tokens = [l.split("#")[0] for l in text.splitlines()]
    words = " ".join(tokens).split()
    if words[0] != "OFF":
        bail("%s is not an OFF file" % member_name)
    nv, nf = int(words[1]), int(words[2])
    mesh = Mesh(os.path.basename(member_name))
    prim = Primitive(materials.add(mesh.name, color))
    pos = 4
    prim.positions.extend(float(w) for w in words[pos: pos + 3 * nv])
    pos += 3 * nv
    for _ in range(nf):
        n = int(words[pos])
        corners = [int(w) for w in words[pos + 1: pos + 1 + n]]
        pos += 1 + n
        for k in range(1, n - 1):
            prim.indices.extend((corners[0], corners[k], corners[k + 1]))
    del prim.normals[:]
    mesh.primitives.append(prim)
    mesh.grow_bounds()
    return mesh


def quad_mesh(name, material, corners):
    """A two-triangle quad; corners counter-clockwise seen from the side its normal points to."""
    mesh = Mesh(name)
    prim = Primitive(material)
    for c in corners:
        prim.positions.extend(c)
    prim.indices.extend((0, 1, 2, 0, 2, 3))
    mesh.primitives.append(prim)
    mesh.grow_bounds()
    return mesh


# ---- layout ----

def quat_y(angle):
    return [0.0, math.sin(angle / 2), 0.0, math.cos(angle / 2)]


def quat_x(angle):
    return [math.sin(angle / 2), 0.0, 0.0, math.cos(angle / 2)]


class Placement:
    """Where one instance of a mesh goes: its footprint centre (x, z), its base height y, the size it is
    scaled to (metres, x = width, y = height, z = depth) and a turn about y."""

    def __init__(self, mesh, size, x=0.0, y=0.0, z=0.0, turn=0.0, name=None):
        self.mesh, self.size, self.x, self.y, self.z, self.turn = mesh, size, x, y, z, turn
        self.name = name or mesh.name

    def node(self, mesh_index):
        m = self.mesh
        scale = []
        for axis in range(3):
            extent = m.hi[axis] - m.lo[axis]
            scale.append(self.size[axis] / extent if extent > 1e-9 else 0.01)
        # The scaled box's bottom centre goes to (x, y, z): T = target - R (S * bottom centre).
        c = (scale[0] * 0.5 * (m.lo[0] + m.hi[0]), scale[1] * m.lo[1], scale[2] * 0.5 * (m.lo[2] + m.hi[2]))
        cos_t, sin_t = math.cos(self.turn), math.sin(self.turn)
        rc = (cos_t * c[0] + sin_t * c[2], c[1], -sin_t * c[0] + cos_t * c[2])
        node = {"name": self.name, "mesh": mesh_index,
                "translation": [self.x - rc[0], self.y - rc[1], self.z - rc[2]], "scale": scale}
        if self.turn:
            node["rotation"] = quat_y(self.turn)
        return node


def catalog_size(piece):
    return (float(piece["width"]) / 100, float(piece["height"]) / 100, float(piece["depth"]) / 100)


def is_small(size):
    return size[1] <= 0.45 and size[0] <= 0.6 and size[2] <= 0.6


GAP = 0.12  # metres between neighbours


def layout_room(pieces, meshes):
    """Floor pieces in rows from the back wall (z = -depth/2) towards the camera, tallest first, each
    facing +z; small pieces on top of tables and cabinets (on the floor when no top has room left).
    Returns (placements, width, depth)."""
    sizes = {p["id"]: catalog_size(p) for p in pieces}
    floor = [p for p in pieces if not is_small(sizes[p["id"]])]
    small = sorted((p for p in pieces if is_small(sizes[p["id"]])), key=lambda p: p["id"])

    # Tops that take small pieces: a surface between 30 cm and 1.2 m high, at least 35 x 30 cm.
    supports = []
    for p in floor:
        w, h, d = sizes[p["id"]]
        top = float(p.get("dropOnTopElevation", "0") or 0) / 100
        if 0.3 < top <= 1.2 and w >= 0.35 and d >= 0.3:
            supports.append({"id": p["id"], "top": top, "w": w, "d": d, "x": 0.03, "z": 0.03, "row": 0.0, "items": []})
    for p in small:  # shelf-pack each top, left to right, back to front
        w, h, d = sizes[p["id"]]
        for s in supports:
            if s["x"] + w > s["w"] - 0.03:
                s["x"], s["z"], s["row"] = 0.03, s["z"] + s["row"] + 0.03, 0.0
            if s["x"] + w <= s["w"] - 0.03 and s["z"] + d <= s["d"] - 0.03:
                s["items"].append((p, s["x"] + w / 2, s["z"] + d / 2))
                s["x"] += w + 0.03
                s["row"] = max(s["row"], d)
                break
        else:
            floor.append(p)

    floor.sort(key=lambda p: (-sizes[p["id"]][1], p["id"]))
    footprint = sum((sizes[p["id"]][0] + GAP) * (sizes[p["id"]][2] + GAP) for p in floor)
    width = max(4.0, max(sizes[p["id"]][0] + 2 * GAP for p in floor), math.sqrt(footprint * 1.6))
    rows, row, x, z, row_depth = [], [], GAP, GAP, 0.0  # x, z: from the left and back walls
    for p in floor:
        w, h, d = sizes[p["id"]]
        if row and x + w > width - GAP:
            rows.append((z, row))
            z += row_depth + GAP
            row, x, row_depth = [], GAP, 0.0
        row.append((p, x + w / 2))
        x += w + GAP
        row_depth = max(row_depth, d)
    rows.append((z, row))
    z += row_depth + GAP
    depth = z + max(2.0, 0.35 * width)  # free floor in front, for the camera

    placements, where = [], {}
    for z_back, row in rows:
        for p, cx in row:
            w, h, d = sizes[p["id"]]
            pl = Placement(meshes[p["id"]], (w, h, d), cx - width / 2, 0.0, z_back + d / 2 - depth / 2)
            placements.append(pl)
            where[p["id"]] = pl
    for s in supports:
        base = where[s["id"]]
        for p, sx, sz in s["items"]:
            placements.append(Placement(meshes[p["id"]], sizes[p["id"]], base.x - s["w"] / 2 + sx, s["top"],
                                        base.z - s["d"] / 2 + sz))
    return placements, width, depth


def room_meshes(materials, width, depth, height, light_count, light_radiance):
    """Floor, ceiling, four walls (each its own object, facing inwards) and one emissive quad mesh."""
    hw, hd = width / 2, depth / 2
    floor_m = materials.add("room/floor", (0.45, 0.32, 0.22))
    wall_m = materials.add("room/wall", (0.75, 0.72, 0.66))
    ceiling_m = materials.add("room/ceiling", (0.8, 0.8, 0.8))
    light_m = materials.add("room/light", (0.8, 0.8, 0.8), [light_radiance] * 3)
    parts = [
        quad_mesh("room/floor", floor_m, [(-hw, 0, hd), (hw, 0, hd), (hw, 0, -hd), (-hw, 0, -hd)]),
        quad_mesh("room/ceiling", ceiling_m, [(-hw, height, -hd), (hw, height, -hd), (hw, height, hd), (-hw, height, hd)]),
        quad_mesh("room/wall-back", wall_m, [(-hw, 0, -hd), (hw, 0, -hd), (hw, height, -hd), (-hw, height, -hd)]),
        quad_mesh("room/wall-front", wall_m, [(hw, 0, hd), (-hw, 0, hd), (-hw, height, hd), (hw, height, hd)]),
        quad_mesh("room/wall-left", wall_m, [(-hw, 0, hd), (-hw, 0, -hd), (-hw, height, -hd), (-hw, height, hd)]),
        quad_mesh("room/wall-right", wall_m, [(hw, 0, -hd), (hw, 0, hd), (hw, height, hd), (hw, height, -hd)]),
    ]
    placements = []
    for m in parts:
        ext = [m.hi[a] - m.lo[a] for a in range(3)]
        placements.append(Placement(m, [e if e > 0 else 1.0 for e in ext], 0.5 * (m.lo[0] + m.hi[0]), m.lo[1],
                                    0.5 * (m.lo[2] + m.hi[2])))
    side = 0.3 * min(width, depth)
    light = quad_mesh("room/light", light_m, [(-0.5, 0, -0.5), (0.5, 0, -0.5), (0.5, 0, 0.5), (-0.5, 0, 0.5)])  # faces down
    for k in range(light_count):
        x = (k + 0.5) / light_count * width - hw
        placements.append(Placement(light, (side, 1.0, side), x, height - 0.02, -0.1 * depth, name="room/light-%d" % k))
    return placements


def camera_node(width, depth, height, look_at):
    """A camera just inside the front wall at eye height, looking at look_at (x = 0)."""
    eye = (0.0, min(1.7, height - 0.4), depth / 2 - 0.15)
    pitch = math.atan2(look_at[1] - eye[1], eye[2] - look_at[2])  # negative: looks down
    return {"name": "camera", "camera": 0, "translation": list(eye), "rotation": quat_x(pitch)}


# ---- glTF 2.0 binary writer ----

def write_glb(path, meshes, placements, materials, camera, yfov):
    bin_chunk = bytearray()
    views, accessors = [], []

    def add(data, target, acc):
        while len(bin_chunk) % 4:
            bin_chunk.append(0)
        views.append({"buffer": 0, "byteOffset": len(bin_chunk), "byteLength": len(data), "target": target})
        bin_chunk.extend(data)
        acc["bufferView"] = len(views) - 1
        accessors.append(acc)
        return len(accessors) - 1

    gl_meshes = []
    for m in meshes:
        prims = []
        for p in m.primitives:
            n = len(p.positions) // 3
            lo = [min(p.positions[a::3]) for a in range(3)]
            hi = [max(p.positions[a::3]) for a in range(3)]
            attrs = {"POSITION": add(p.positions.tobytes(), 34962,
                                     {"componentType": 5126, "count": n, "type": "VEC3", "min": lo, "max": hi})}
            if len(p.normals):
                attrs["NORMAL"] = add(p.normals.tobytes(), 34962, {"componentType": 5126, "count": n, "type": "VEC3"})
            if n <= 65536:
                idx, ctype = array.array("H", p.indices).tobytes(), 5123
            else:
                idx, ctype = p.indices.tobytes(), 5125
            prims.append({"attributes": attrs, "material": p.material, "mode": 4,
                          "indices": add(idx, 34963, {"componentType": ctype, "count": len(p.indices), "type": "SCALAR"})})
        gl_meshes.append({"name": m.name, "primitives": prims})

    gl_materials = []
    for mat in materials.items:
        g = {"name": mat["name"], "pbrMetallicRoughness": {"baseColorFactor": list(mat["color"]) + [1.0],
                                                            "metallicFactor": 0.0, "roughnessFactor": 1.0}}
        extensions = []
        if mat["emission"]:
            peak = max(mat["emission"])
            if peak > 1.0:  # emissiveFactor stops at 1: the rest is KHR_materials_emissive_strength
                g["emissiveFactor"] = [e / peak for e in mat["emission"]]
                g["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": peak}}
                extensions.append("KHR_materials_emissive_strength")
            else:
                g["emissiveFactor"] = list(mat["emission"])
        gl_materials.append(g)

    mesh_index = {id(m): k for k, m in enumerate(meshes)}
    nodes = [pl.node(mesh_index[id(pl.mesh)]) for pl in placements] + [camera]
    doc = {
        "asset": {"version": "2.0", "generator": "linespace scenes/assemble_real_scenes.py"},
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": gl_meshes,
        "materials": gl_materials,
        "cameras": [{"type": "perspective", "perspective": {"yfov": yfov, "znear": 0.05, "aspectRatio": 1.0}}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(bin_chunk)}],
    }
    if any(m["emission"] and max(m["emission"]) > 1.0 for m in materials.items):
        doc["extensionsUsed"] = ["KHR_materials_emissive_strength"]
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    while len(bin_chunk) % 4:
        bin_chunk.append(0)
    total = 12 + 8 + len(text) + 8 + len(bin_chunk)
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(struct.pack("<4sII", b"glTF", 2, total))
        f.write(struct.pack("<I4s", len(text), b"JSON") + text)
        f.write(struct.pack("<I4s", len(bin_chunk), b"BIN\0"))
        f.write(bin_chunk)
    os.replace(tmp, path)
    return total


# ---- assembling one scene ----

def input_signature():
    """Changes when this script or an input package changes: outputs with another one are rebuilt."""
    h = hashlib.sha256(open(os.path.abspath(__file__), "rb").read())
    for path in sorted(glob.glob(os.path.join(FURNITURE_DIR, "*.sh3f"))) + CGAL_DATA:
        if os.path.exists(path):
            st = os.stat(path)
            h.update(("%s %d %d\n" % (path, st.st_size, int(st.st_mtime))).encode())
    return h.hexdigest()


def model_rotation(piece):
    if "modelRotation" not in piece:
        return None
    m = [float(v) for v in piece["modelRotation"].split()]
    if len(m) != 9:
        bail("%s: modelRotation needs 9 numbers" % piece["id"])
    return m


def credit(piece):
    catalog = piece["catalog"]
    entry = {"id": piece["id"], "name": piece.get("name", ""), "creator": piece.get("creator", ""),
             "license": catalog.license, "catalog": catalog.name + ".sh3f", "package": "sweethome3d-furniture",
             "model": piece["model"].lstrip("/")}
    note = catalog.source_note(piece)
    if note:
        entry["source"] = note
    return entry


def assemble(name, recipe, catalogs, out_dir):
    t0 = time.time()
    index = {}
    for c in catalogs.values():
        index.update(c.pieces)
    missing = [i for i in recipe["furniture"] if i not in index]
    if missing:
        bail("%s: the installed catalogs lack %s" % (name, ", ".join(missing)))
    pieces = [index[i] for i in recipe["furniture"]]
    materials = Materials()
    meshes = {}
    for p in pieces:
        try:
            meshes[p["id"]] = read_obj(p["catalog"], p, materials, model_rotation(p))
        except (KeyError, ValueError, IndexError) as e:  # a damaged or changed package
            bail("%s: cannot read %s from %s (%s: %s)" % (name, p["model"], p["catalog"].path, type(e).__name__, e))
    credits = [credit(p) for p in pieces]

    placements, width, depth = layout_room(pieces, meshes)
    if "bunny" in recipe:  # 8 x 8 bunnies in front of the furniture
        b = recipe["bunny"]
        bunny = read_off_from_tar(b["member"], materials, (0.7, 0.55, 0.4))
        ext = [bunny.hi[a] - bunny.lo[a] for a in range(3)]
        k = b["height"] / ext[1]
        size = (ext[0] * k, b["height"], ext[2] * k)
        n = b["grid"]
        pitch = max(size[0], size[2]) * 1.25
        depth = max(depth, 1.6 * n * pitch + 2.5)
        width = max(width, n * pitch + 1.0)
        for i in range(n):
            for j in range(n):
                placements.append(Placement(bunny, size, (i - (n - 1) / 2) * pitch, 0.0, (j - (n - 1) / 2) * pitch + 0.2,
                                            turn=0.35 * ((i * 7 + j * 3) % 9), name="bunny-%d-%d" % (i, j)))
        credits.append({"id": b["member"], "name": "Stanford Bunny (%s)" % os.path.basename(b["member"]),
                        "creator": "Stanford Computer Graphics Laboratory (3D scan); CGAL project (file)",
                        "license": "CGAL: CC0-1.0 for data files without a notice; Stanford 3D Scanning Repository: "
                                   "free use, please acknowledge",
                        "catalog": "data.tar.gz", "package": "libcgal-demo", "model": b["member"]})
    tallest = max(pl.y + pl.size[1] for pl in placements)
    height = max(2.7, tallest + 0.3)
    placements += room_meshes(materials, width, depth, height, recipe.get("lights", 1), recipe.get("light_radiance", 12.0))

    unique = []
    for pl in placements:
        if pl.mesh not in unique:
            unique.append(pl.mesh)
    look_at = (0.0, 0.5, -depth / 4)
    camera = camera_node(width, depth, height, look_at)
    path = os.path.join(out_dir, name + ".glb")
    size = write_glb(path, unique, placements, materials, camera, recipe.get("yfov", 1.0))
    counts = {"objects": len(unique), "instances": len(placements),
              "triangles": sum(pl.mesh.triangles() for pl in placements)}
    manifest = {"scene": name, "title": recipe["title"], "file": os.path.basename(path), "bytes": size,
                "signature": input_signature(), "counts": counts,
                "targets": {k: recipe[k] for k in ("objects", "triangles", "instances") if k in recipe},
                "room_metres": [round(width, 3), round(height, 3), round(depth, 3)],
                "seconds": round(time.time() - t0, 2), "models": credits}
    with open(os.path.join(out_dir, name + ".json"), "w") as f:
        json.dump(manifest, f, indent=1)
    return manifest


def off_target(manifest):
    """Counts more than 10 % from the paper's (objects, triangles, instances where given)."""
    bad = []
    for key, target in manifest["targets"].items():
        got = manifest["counts"][key]
        if abs(got - target) > 0.1 * target:
            bad.append("%s %d (target %d)" % (key, got, target))
    return bad


def write_credits(out_dir):
    """CREDITS.md for every scene in out_dir (their .json manifests)."""
    lines = ["# Credits for the assembled scenes in this folder", "",
             "Written by scenes/assemble_real_scenes.py.  The furniture comes from the Debian package",
             "sweethome3d-furniture (licences: /usr/share/doc/sweethome3d-furniture/copyright; CC0-1.0 and",
             "CC-BY-3.0 / CC-BY-3.0-US, https://creativecommons.org/licenses/by/3.0/); the bunny from libcgal-demo",
             "(/usr/share/doc/libcgal-demo/copyright).  The models were scaled, placed and converted to glTF.", ""]
    for mpath in sorted(glob.glob(os.path.join(out_dir, "*.json"))):
        try:
            m = json.load(open(mpath))
        except ValueError:
            continue
        if "models" not in m:
            continue
        lines += ["## %s (%s)" % (m["file"], m["title"]), ""]
        for c in m["models"]:
            line = "- `%s` \"%s\" by %s; licence %s; %s from %s (package %s)" % (
                c["id"], c["name"], c["creator"], c["license"], c["model"], c["catalog"], c["package"])
            src = c.get("source")
            if src:
                line += "; original \"%s\", %s, %s" % (src.get("title", "?"), src.get("license", "?"), src.get("url", "?"))
            lines.append(line)
        lines.append("")
    tmp = os.path.join(out_dir, "CREDITS.md.tmp")
    with open(tmp, "w") as f:
        f.write("\n".join(lines))
    os.replace(tmp, os.path.join(out_dir, "CREDITS.md"))


def up_to_date(name, out_dir, signature):
    try:
        m = json.load(open(os.path.join(out_dir, name + ".json")))
    except (OSError, ValueError):
        return None
    if m.get("signature") == signature and os.path.exists(os.path.join(out_dir, m.get("file", ""))):
        return m
    return None


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenes", nargs="*", help="scene names: " + ", ".join(SCENES))
    parser.add_argument("--all", action="store_true", help="all five scenes")
    parser.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "assets", "real"),
                        help="output folder (default: assets/real in the repository)")
    parser.add_argument("--force", action="store_true", help="rebuild scenes that are up to date")
    args = parser.parse_args()
    names = list(SCENES) if args.all else args.scenes
    if not names:
        bail("name the scenes to assemble (%s) or pass --all" % ", ".join(SCENES))
    unknown = [n for n in names if n not in SCENES]
    if unknown:
        bail("unknown scene %s (known: %s)" % (", ".join(unknown), ", ".join(SCENES)))
    out_dir = os.path.normpath(args.out)
    os.makedirs(out_dir, exist_ok=True)
    catalogs = open_catalogs()
    signature = input_signature()
    failed = False
    for name in names:
        m = None if args.force else up_to_date(name, out_dir, signature)
        state = "up to date"
        if m is None:
            m = assemble(name, SCENES[name], catalogs, out_dir)
            state = "assembled in %.1f s" % m["seconds"]
        c = m["counts"]
        bad = off_target(m)
        print("%-14s %s: %d objects, %d instances, %d triangles, %.1f MB (%s)%s" % (
            name, os.path.join(out_dir, m["file"]), c["objects"], c["instances"], c["triangles"], m["bytes"] / 1e6, state,
            "; OFF TARGET: " + ", ".join(bad) if bad else ""))
        failed = failed or bool(bad)
    write_credits(out_dir)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
