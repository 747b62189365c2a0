"""ArticulationDamper's figures at the HubnerDamper estimates (prints; not a test):
Mmax at 0/30/50 deg for both directions, the torque at 34 % and 0.2 rad/s, and
the rotational damping d|Mjoint|/dLambdaDot at small rates at 34 % (the
co-simulation stability figure h c / J for J = 5e4 kg m2 at a 10 ms step)."""
import math

from artibus import fmu_dir
from artibus.fmu import Fmu

DEG = math.pi / 180
OUTS = ["Mjoint", "Mmax", "F[1]", "F[2]", "Ldot[1]", "Ldot[2]"]


def main():
    with Fmu(fmu_dir() / "ArticulationDamper.fmu") as f:
        f.initialize({})

        def at(lam, rate, pct):
            f.set_values({"Lambda": lam * DEG, "LambdaDot": rate, "pct": pct})
            return dict(zip(OUTS, f.get(*OUTS)))

        print("Mmax [kN.m] (50 %, |Ldot| >> v0)   bend increasing   bend decreasing   at rest")
        for lam in (0, 30, 50):
            up, down, rest = at(lam, 1.0, 50)["Mmax"], at(lam, -1.0, 50)["Mmax"], at(lam, 0.0, 50)["Mmax"]
            print(f"  Lambda = {lam:2d} deg                  {up / 1e3:8.2f}          {down / 1e3:8.2f}      {rest / 1e3:8.2f}")
        print("torque at 34 %, LambdaDot = 0.2 rad/s [kN.m] (and its piston speed):")
        for lam in (0, 30, 50):
            o = at(lam, 0.2, 34.0)
            print(f"  Lambda = {lam:2d} deg: Mjoint = {o['Mjoint'] / 1e3:7.2f}  "
                  f"(Ldot[1] = {o['Ldot[1]'] * 1e3:6.1f} mm/s, (pct/50) Mmax = {0.68 * o['Mmax'] / 1e3:6.2f})")
        print("rotational damping at small rates, 34 % [N.m.s/rad] and h c / J at h = 10 ms, J = 5e4 kg m2:")
        for lam in (0, 30, 50):
            d = 1e-5
            c = abs(at(lam, d, 34.0)["Mjoint"]) / d
            c50 = abs(at(lam, d, 50.0)["Mjoint"]) / d
            print(f"  Lambda = {lam:2d} deg: c = {c:9.3e} (h c/J = {0.01 * c / 5e4:.3f}); at 50 %: {c50:9.3e} "
                  f"(h c/J = {0.01 * c50 / 5e4:.3f})")
        print("secant damping |Mjoint|/LambdaDot at 34 %, Lambda = 0:")
        for rate in (0.001, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5):
            print(f"  LambdaDot = {rate:5.3f} rad/s: {abs(at(0, rate, 34.0)['Mjoint']) / rate:9.3e}")


if __name__ == "__main__":
    main()
