"""One episode played: the loop of observations, actions, simulator steps and rules (`episode_loop`), the
decentralized team of the `silent` and `comm` modes (`agents`) and its message channel (`channel`).

Flows in: an episode, a simulator and a team policy. Flows out: the episode's trajectory and records.
"""
