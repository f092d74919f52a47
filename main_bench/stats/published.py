"""Episode lengths other navigation data sets publish, each with its exact source (the Fig. 3(a) comparison).

Only figures found in a source are kept, in the form the source gives them: a range stays a range, a mean stays a
mean; nothing here is a distribution that no one published. A figure of kind `episode_files` is computed from
episode files a data set's authors publish (Habitat ObjectNav's `val_mini` samples): per scene the mean of the
episodes' `info.geodesic_distance` (metres, start to the closest goal view point), and over all of the file's
episodes the median, minimum and maximum; the file is named by repository, commit and path. Data sets whose
figures were looked for and not found are listed in `NOT_FOUND` with what was looked for, so the figure and the
docs can say they are missing.
"""

from __future__ import annotations

from dataclasses import dataclass

#: How a published figure is drawn: a range (low..high); a single value (a mean or a median); or the summary of
#: published episode files (`episode_files`: per-scene means, and the median with the min..max of every episode).
KINDS = ("range", "mean", "median", "episode_files")


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
    #: `episode_files` only: (scene, episodes, mean geodesic distance in metres) per scene of the files.
    scene_means: tuple[tuple[str, int, float], ...] = ()

    def episodes(self) -> int | None:
        """Episodes the figure is computed from (`episode_files`), else None."""
        return sum(n for _, n, _ in self.scene_means) if self.scene_means else None

    def label(self) -> str:
        """Short text for a plot: data set and what was measured."""
        return f"{self.dataset}: {self.quantity}"


@dataclass(frozen=True)
class MissingFigure:
    """A data set whose episode-length figure was looked for in stored sources and not found."""

    dataset: str
    looked_for: str


_CHALLENGE = "https://github.com/facebookresearch/habitat-challenge/blob/"


def _val_mini(dataset: str, paper: str, commit: str, when: str, path: str, files: str,
              scene_means: tuple[tuple[str, int, float], ...], median: float, low: float,
              high: float) -> PublishedLength:
    """A Habitat ObjectNav `val_mini` sample from facebookresearch/habitat-challenge at `commit`: `path` is its
    folder, `files` the episode files in it; per scene (name, episodes, mean `info.geodesic_distance` in metres)
    and the median, minimum and maximum over all of its episodes."""
    return PublishedLength(
        dataset=f"Habitat ObjectNav, {dataset}, val_mini", quantity="start to goal: scene means, every episode",
        kind="episode_files", low_m=low, high_m=high, value_m=median,
        source=(f"Habitat ObjectNav episodes ({paper}); the official val_mini sample of the split's episodes, "
                "published with the Habitat Challenge's starter code; per scene the mean of "
                "info.geodesic_distance (metres)"),
        where=f"GitHub facebookresearch/habitat-challenge, commit {commit} ({when}), {path}/{files}",
        url=f"{_CHALLENGE}{commit}/{path}", scene_means=scene_means)


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
    _val_mini("Matterport3D v1 (Habitat Challenge 2020 and 2021)",
              "D. Batra et al.: ObjectNav Revisited: On Evaluation of Embodied Agents Navigating to Objects, "
              "arXiv 2006.13171, 2020", "dc780000cdba7fe649f8352fc2ecfba3143c00ef",
              "2020-03-20; the same file on branch challenge-2021", "habitat-challenge-data/objectgoal_mp3d/val_mini",
              "val_mini.json.gz", (("x8F5xyUWy9e", 30, 6.347),), median=5.604, low=1.428, high=13.659),
    _val_mini("HM3D v1 (Habitat Challenge 2022)",
              "on HM3D, S. K. Ramakrishnan et al.: Habitat-Matterport 3D Dataset (HM3D), arXiv 2109.08238, 2021",
              "ab87aa66d747eabe337328e5d39d71bcc78078a5", "2022-03-11; branch challenge-2022",
              "habitat-challenge-data/objectgoal_hm3d/val_mini/content", "TEEsavR23oF.json.gz and wcojb4TFT35.json.gz",
              (("TEEsavR23oF", 15, 11.497), ("wcojb4TFT35", 15, 6.207)), median=6.526, low=3.021, high=26.246),
    _val_mini("HM3D v2 (Habitat Challenge 2023)",
              "on HM3D-Semantics, K. Yadav et al.: Habitat-Matterport 3D Semantics Dataset, arXiv 2210.05633, 2023",
              "40cb2a6f5969400fe0d2981eb9caeff54d4ea7dc", "2023-03-20",
              "habitat-challenge-data/data/datasets/objectnav/hm3d/v2/val_mini/content",
              "TEEsavR23oF.json.gz and wcojb4TFT35.json.gz",
              (("TEEsavR23oF", 15, 5.603), ("wcojb4TFT35", 15, 3.861)), median=4.153, low=1.054, high=10.139),
)

NOT_FOUND: tuple[MissingFigure, ...] = (
    MissingFigure("Habitat ObjectNav, full val and train splits (Matterport3D v1, HM3D v1 and v2)",
                  "a published mean, median or range of the start-to-goal geodesic distance over a whole split "
                  "(ObjectNav Revisited, arXiv 2006.13171; the stored openings of the HM3D and HM3D-Semantics "
                  "papers; aihabitat.org/challenge/2020 to /2023; the habitat-challenge README); the split files "
                  "themselves were not reachable"),
)
