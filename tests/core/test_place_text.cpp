// rewrite_places: the places a finished message names, written anew where it is printed.
#include <gtest/gtest.h>

#include "polysquare/core/place_text.h"
#include "polysquare/pipeline/check_options.h"

namespace polysquare {
namespace {

// Writes a place moved by (1000, -1000), so that a test sees both the place found and its numbers read.
std::string moved(Vec2 p) { return "<" + plain_point_text({p.x + 1000, p.y - 1000}) + ">"; }

TEST(PlaceText, EveryWriterOfPlacesIsFoundAndRead) {
  const Vec2 p{512345.25, -4178000.5};
  for (const std::string& place : {at_text(p), plain_point_text(p), point_text(p),
                                   "(" + short_number(p.x) + ", " + short_number(p.y) + ")"})
    EXPECT_EQ(rewrite_places("patch: node at " + place + " is in no quad", moved),
              "patch: node at " + moved({std::stod(place.substr(1)), std::stod(place.substr(place.find(", ") + 2))}) +
                  " is in no quad")
        << place;
  EXPECT_EQ(rewrite_places("from (1.5, 2) to (3, -4e-07).", moved), "from <(1001.5, -998)> to <(1003, -1000.0000004)>.");
}

TEST(PlaceText, OtherParenthesesStayAsTheyAre) {
  for (const std::string text :
       {"sides 1 and 2 of the poly-square overlap at (3, 5)", "part 2 (3 quads, 4 nodes)", "(1.5, 2.5, 3.5)",
        "a quad at (1.5, 2.5", "(1.5,2.5)", "(nan, 2.5)", "(inf, 2.5)", "(, )", "((", "no place", ""})
    EXPECT_EQ(rewrite_places(text, moved), text);
  EXPECT_EQ(rewrite_places("((1.5, 2.5)) (places relative to (1e+06, 2))", moved),
            "(<(1001.5, -997.5)>) (places relative to <(1001000, -998)>)");
}

}  // namespace
}  // namespace polysquare
