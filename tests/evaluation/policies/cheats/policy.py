"""The cheaters as one folder submission (a file spec shows its file alone, and they share `cheat_common`):
`cheats:Spy` reads the data set's answers, `cheats:Forge` rewrites finished results, `cheats:HonestTwin` plays
as the forge does without forging."""

from forge import HonestTwin
from forge import Policy as Forge
from spy import Policy as Spy

__all__ = ["Forge", "HonestTwin", "Spy"]
