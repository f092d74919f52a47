"""Node names of scene files mapped to categories: common furniture naming, CamelCase, numbered copies."""

from __future__ import annotations

import pytest

from main_bench.scenes.objects import KNOWN_CATEGORIES, category_from_node_name

TABLE = [
    # pictures
    ("Portrait_3", "picture"), ("painting_02", "picture"), ("Poster.001", "picture"), ("WallArt_01", "picture"),
    ("PictureFrame_2", "picture"), ("photo_frame_1", "picture"), ("picture", "picture"),
    # trash cans
    ("TrashCan", "trash_can"), ("trash_can_4", "trash_can"), ("Bin_3", "trash_can"), ("WasteBasket_01", "trash_can"),
    ("garbage_can.002", "trash_can"), ("TrashBin", "trash_can"),
    # seating
    ("ChairA_01_001", "chair"), ("OfficeChair_2", "chair"), ("Couch_1", "sofa"), ("Loveseat", "sofa"),
    ("ArmChair_3", "armchair"), ("armchair", "armchair"), ("Ottoman_1", "stool"), ("Bench_02", "seating"),
    # tables and storage
    ("CoffeeTable_01", "coffee_table"), ("DiningTable_1", "table"), ("NightStand_01_002", "nightstand"),
    ("BedsideTable_1", "nightstand"), ("TVCabinet_01_001", "cabinet"), ("Cupboard_3", "cabinet"),
    ("Bookcase_1", "bookshelf"), ("Shelves_2", "shelf"), ("ChestOfDrawers_1", "chest_of_drawers"),
    # appliances and fixtures
    ("Fridge_1", "refrigerator"), ("Television_01", "tv"), ("TV_2", "tv"), ("MicrowaveOven_1", "microwave"),
    ("Washbasin_1", "sink"), ("BathTub_1", "bathtub"), ("PottedPlant_3", "plant"), ("Houseplant", "plant"),
    ("Pillow_4", "cushion"), ("obj:chair:3", "chair"), ("coffee_table.001", "coffee_table"),
    # not objects, or too generic to read from a name
    ("Wall_01", None), ("Floor", None), ("Objects", None), ("Furniture_Group", None), ("node_17", None),
]


@pytest.mark.parametrize(("name", "category"), TABLE)
def test_node_name_table(name, category):
    assert category_from_node_name(name) == category


def test_known_categories_keep_their_ids():
    """Observation targets are indices into KNOWN_CATEGORIES: new names are appended, old ids do not move."""
    assert KNOWN_CATEGORIES[:3] == ("bathtub", "bed", "bookshelf") and KNOWN_CATEGORIES[35] == "coffee_table"
    assert KNOWN_CATEGORIES[-1] == "trash_can" and len(set(KNOWN_CATEGORIES)) == len(KNOWN_CATEGORIES)
