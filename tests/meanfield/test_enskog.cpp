// Enskog collision frequency, Haff's time constant and the charging-rate exponent
// (meanfield/kinetic/Cooling.h, Charging.h) against the reference numbers of docs/model.md section
// 8.
#include <catch2/catch.hpp>

#include <cmath>
#include <stdexcept>

#include "meanfield/kinetic/Charging.h"
#include "meanfield/kinetic/Cooling.h"

using namespace granagg::meanfield;

TEST_CASE("Enskog collision frequency at phi = 0.076 matches the reference values",
          "[meanfield][kinetic][enskog]") {
  // docs/model.md section 8 quotes n = 0.145149, g2 = 1.219436, omega = 1.25490: margins of half a
  // unit in the last quoted digit (plus round-off).
  CHECK(numberDensity(0.076) == Approx(0.145149).epsilon(0).margin(6e-7));
  CHECK(carnahanStarlingG2(0.076) == Approx(1.219436).epsilon(0).margin(6e-7));
  CHECK(enskogCollisionFrequency(0.076, 1.0) == Approx(1.25490).epsilon(0).margin(1e-5));
  // omega ~ sqrt(T); dilute limit g2 -> 1 + 5 phi / 2 (Carnahan-Starling expanded).
  CHECK(enskogCollisionFrequency(0.076, 4.0) ==
        Approx(2.0 * enskogCollisionFrequency(0.076, 1.0)).epsilon(1e-15));
  CHECK(carnahanStarlingG2(1e-6) == Approx(1.0 + 2.5e-6).epsilon(1e-11));
  CHECK(enskogCollisionFrequency(0.076, 0.0) == 0.0);
}

TEST_CASE("Haff time constant and temperature", "[meanfield][kinetic][enskog]") {
  // 1/tau0 = (1 - eps^2) omega0 / 6: at eps = 0.9, phi = 0.076 this is 0.19 * 1.25490 / 6.
  CHECK(haffInverseTau0(0.9, 0.076) == Approx(0.19 * 1.2548998 / 6.0).epsilon(1e-7));
  CHECK(haffInverseTau0(1.0, 0.076) == 0.0);
  const double tau0 = 1.0 / haffInverseTau0(0.5, 0.076);
  CHECK(haffTemperature(tau0, 0.5, 0.076) == Approx(0.25).epsilon(1e-14));  // (1 + 1)^-2
  CHECK(haffTemperature(0.0, 0.5, 0.076, 2.0) == 2.0);
}

TEST_CASE("charging-rate exponent", "[meanfield][kinetic][charging]") {
  // docs/model.md section 8: -5/6 - 5 kappa / 3, i.e. -13/6 at kappa = 0.8.
  CHECK(chargingRateExponent(0.8) == Approx(-13.0 / 6.0).epsilon(1e-15));
  CHECK(chargingRateExponent(0.83) == Approx(-5.0 / 6.0 - 5.0 * 0.83 / 3.0).epsilon(1e-15));
  CHECK(chargingRateExponent(0.0) == Approx(-5.0 / 6.0).epsilon(1e-15));
  CHECK(chargingRateExponent(0.8, 2.0) == Approx(-2.6).epsilon(1e-15));  // Haff cooling
  CHECK_THROWS_AS(chargingRateExponent(-0.1), std::invalid_argument);
  CHECK_THROWS_AS(chargingRateExponent(std::nan("")), std::invalid_argument);
  CHECK_THROWS_AS(chargingRateExponent(0.8, 0.0), std::invalid_argument);
}

TEST_CASE("kinetic-theory functions reject bad parameters", "[meanfield][kinetic][enskog]") {
  CHECK_THROWS_AS(numberDensity(0.0), std::invalid_argument);
  CHECK_THROWS_AS(carnahanStarlingG2(0.74), std::invalid_argument);
  CHECK_THROWS_AS(enskogCollisionFrequency(-0.1, 1.0), std::invalid_argument);
  CHECK_THROWS_AS(enskogCollisionFrequency(0.076, -1.0), std::invalid_argument);
  CHECK_THROWS_WITH(numberDensity(0.8), Catch::Contains("phi") && Catch::Contains("0.8"));
  CHECK_THROWS_AS(haffInverseTau0(1.1, 0.076), std::invalid_argument);
  CHECK_THROWS_AS(haffInverseTau0(-0.1, 0.076), std::invalid_argument);
  CHECK_THROWS_AS(haffInverseTau0(0.9, 0.076, 0.0), std::invalid_argument);
  CHECK_THROWS_AS(haffTemperature(-1.0, 0.9, 0.076), std::invalid_argument);
}
