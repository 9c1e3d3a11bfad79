"""The run's progress bar: frames done, running rate in Hz, frames lost so far."""

from __future__ import annotations

from collections import deque


class RateBar:
    """A tqdm bar whose postfix shows the rate of the last ``window`` frames in Hz (tqdm's
    own rate smooths over the whole run and hides a slowdown) and the lost-frame count."""

    def __init__(self, total: int, desc: str, enabled: bool = True, window: int = 20) -> None:
        from tqdm import tqdm

        # tqdm's own it/s column is left out: the postfix carries the rate
        self._bar = tqdm(total=total, desc=desc, unit="frame", disable=not enabled,
                         dynamic_ncols=True, bar_format="{l_bar}{bar}| {n_fmt}/{total_fmt} "
                         "[{elapsed}<{remaining}{postfix}]")
        self._recent: deque[float] = deque(maxlen=window)
        self.lost = 0

    def step(self, frame_ms: float, status: str) -> None:
        self._recent.append(frame_ms)
        self.lost += status == "lost"
        seconds = sum(self._recent) / 1e3
        hz = len(self._recent) / seconds if seconds > 0 else float("inf")
        postfix = f"{hz:.1f} Hz" + (f", {self.lost} lost" if self.lost else "")
        self._bar.set_postfix_str(postfix, refresh=False)
        self._bar.update(1)

    def close(self) -> None:
        self._bar.close()

    def __enter__(self) -> "RateBar":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
