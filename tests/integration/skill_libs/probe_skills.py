"""A skill that reads the process's `probe` interface."""

from skillbus.robot import interfaces
from skillbus.skill import PrimitiveBase, SkillDescription


class ReadProbe(SkillDescription):
    def createDescription(self):
        pass


class read_probe(PrimitiveBase):
    def createDescription(self):
        self.setDescription(ReadProbe(), "read_probe")

    def execute(self):
        try:
            probe = interfaces.get("probe")
        except interfaces.InterfaceError as e:
            return self.fail(str(e), -1)
        return self.success(f"probe says {probe.arg}")
