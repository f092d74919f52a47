"""Episode lengths other navigation data sets publish, each with its exact source (the Fig. 3(a) comparison).

Only figures found in a source are kept, in the form the source gives them: a range stays a range, a mean stays a
mean; nothing here is a distribution that no one published. Data sets whose figures were looked for and not found
are listed in `NOT_FOUND` with what was looked for, so the figure and the docs can say they are missing.
"""

from __future__ import annotations

from dataclasses import dataclass

#: How a published figure is drawn: a range (low..high), or a single value (a mean or a median).
KINDS = ("range", "mean", "median")


@dataclass(frozen=True)
class PublishedLength:
    """One published episode-length figure (metres) of another data set, and where it is published."""

    dataset: str
    quantity: str
    kind: str
    low_m: float | None
    high_m: float | None
    value_m: float | None
    source: str
    where: str
    url: str

    def label(self) -> str:
        """Short text for a plot: data set and what was measured."""
        return f"{self.dataset}: {self.quantity}"


@dataclass(frozen=True)
class MissingFigure:
    """A data set whose episode-length figure was looked for in stored sources and not found."""

    dataset: str
    looked_for: str


PUBLISHED_LENGTHS: tuple[PublishedLength, ...] = (
    PublishedLength(
        dataset="MultiON (Matterport3D; 1-ON, 2-ON, 3-ON)",
        quantity="geodesic distance of each leg (start to first goal, goal to next goal), constrained",
        kind="range",
        low_m=2.0,
        high_m=20.0,
        value_m=None,
        source=("S. Wani, S. Patel, U. Jain, A. X. Chang, M. Savva: MultiON: Benchmarking Semantic Map Memory "
                "using Multi-Object Navigation, NeurIPS 2020; episode generation as stated by the first author"),
        where="GitHub saimwani/multiON issue #9 'How the multiON dataset is generated?', comment of 2021-04-21",
        url="https://github.com/saimwani/multiON/issues/9",
    ),
)

NOT_FOUND: tuple[MissingFigure, ...] = (
    MissingFigure("Habitat ObjectNav, Matterport3D (Habitat Challenge 2020/2021)",
                  "mean, median or range of the start-to-goal geodesic distance (ObjectNav Revisited, "
                  "arXiv 2006.13171; aihabitat.org/challenge/2020 and /2021; habitat-challenge README)"),
    MissingFigure("Habitat ObjectNav, HM3D (Habitat Challenge 2022/2023)",
                  "mean, median or range of the start-to-goal geodesic distance (aihabitat.org/challenge/2022 "
                  "and /2023; habitat-challenge README)"),
)
