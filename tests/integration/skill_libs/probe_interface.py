"""A robot interface for the tests of interfaces by name: it only remembers its argument."""


class Probe:
    def __init__(self, arg: str, lockstep: bool) -> None:
        self.arg, self.lockstep = arg, lockstep


def interface(bus, participant, arg, **options):
    return Probe(arg, participant is not None)
