"""The head behind the board's pins: the stages, the laser and the
photodiode, in a process of its own (`board-plant`, the simulated head's
world from `gonio_sim::plant`), so that the optics are the simulated
head's and nothing here reads the firmware's variables.

Output changes go to it as they happen, unanswered (buffered until the
next question); the home switches are asked for when the image reads
their port, and conversions when the ADC completes them. Times are the
board's cycles."""

import json
import subprocess


class Plant:
    def __init__(self, command: list[str]) -> None:
        self.proc = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, bufsize=1 << 16)
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.stdin, self.stdout = self.proc.stdin, self.proc.stdout
        line = self.stdout.readline()
        if not line:
            raise RuntimeError(f"{command[0]} did not start (exit {self.proc.wait()})")
        header = json.loads(line)
        self.outputs: set[str] = set(header["outputs"])
        self.switches: list[str] = header["switches"]
        self.photodiode: str = header["photodiode"]

    def output(self, cycle: int, pin: str, level: int) -> None:
        if pin in self.outputs:
            self.stdin.write(f"p {cycle} {pin} {level}\n")

    def _ask(self, line: str) -> str:
        self.stdin.write(line + "\n")
        self.stdin.flush()
        answer = self.stdout.readline()
        if not answer:
            raise RuntimeError(f"board-plant ended (exit {self.proc.poll()})")
        return answer.strip()

    def switch_levels(self, cycle: int) -> dict[str, int]:
        """{pin: level} of the home switches' lines at `cycle`."""
        return dict(zip(self.switches, map(int, self._ask(f"s {cycle}").split()), strict=False))

    def convert(self, n: int, start: float, step: float) -> bytes:
        """The codes (little-endian 16-bit bytes) of `n` conversions sampled
        at `start + k·step` cycles."""
        return bytes.fromhex(self._ask(f"c {n} {start!r} {step!r}"))

    def close(self) -> None:
        self.stdin.close()
        self.proc.wait(timeout=5)
