// The SEIF's block-sparse store on its own: links symmetric and counted once, H and b as
// added, gather/scatter exact, robot links consistent after removal, relaxation converging.
#include <seif/core/errors.hpp>
#include "filters/seif_store.hpp"

#include <Eigen/Cholesky>
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <stdexcept>
#include <vector>

namespace {

using namespace seif;
using Mat5 = Eigen::Matrix<double, 5, 5>;
using Vec5 = Eigen::Matrix<double, 5, 1>;

const Mat3 kRobotH = Vec3(4.0, 5.0, 6.0).asDiagonal();
const Vec3 kRobotMean(1.0, -2.0, 0.5);

/// A positive definite 5x5 block and a vector over [robot, landmark], from `rng`.
std::pair<Mat5, Vec5> randomInformation(std::mt19937_64& rng) {
  std::normal_distribution<double> n01;
  Mat5 A;
  Vec5 b;
  for (int i = 0; i < 5; ++i) {
    b(i) = n01(rng);
    for (int j = 0; j < 5; ++j) A(i, j) = n01(rng);
  }
  return {A * A.transpose() + Mat5::Identity(), b};
}

Mat2 randomBlock(std::mt19937_64& rng) {
  std::normal_distribution<double> n01;
  return Mat2{{0.1 * n01(rng), 0.1 * n01(rng)}, {0.1 * n01(rng), 0.1 * n01(rng)}};
}

/// A store of `n` landmarks (ids 10, 11, ...), each observed once, and the same H and b
/// assembled densely beside it; landmarks 0-1, 1-2 and 0-3 linked.
struct Fixture {
  SeifStore store{kRobotH, kRobotMean};
  Eigen::MatrixXd H;
  Eigen::VectorXd b;

  explicit Fixture(int n, std::uint64_t seed = 1) : H(3 + 2 * n, 3 + 2 * n), b(3 + 2 * n) {
    std::mt19937_64 rng(seed);
    H.setZero();
    H.topLeftCorner<3, 3>() = kRobotH;
    b.setZero();
    b.head<3>() = kRobotH * kRobotMean;
    for (int s = 0; s < n; ++s) {
      EXPECT_EQ(store.addLandmark(10 + s, Vec2(s, -s)), s);
      const auto [dH, db] = randomInformation(rng);
      store.addObservation(s, dH, db);
      const int i = StateLayout::landmark(s);
      b.head<3>() += db.head<3>();
      b.segment<2>(i) += db.tail<2>();
      H.topLeftCorner<3, 3>() += dH.topLeftCorner<3, 3>();
      H.block<3, 2>(0, i) += dH.topRightCorner<3, 2>();
      H.block<2, 3>(i, 0) += dH.topRightCorner<3, 2>().transpose();
      H.block<2, 2>(i, i) += dH.bottomRightCorner<2, 2>();
    }
    for (const auto& [a, c] : {std::pair{0, 1}, std::pair{1, 2}, std::pair{0, 3}}) {
      if (c >= n) continue;
      const Mat2 B = randomBlock(rng);
      store.addToLink(a, c, B);
      H.block<2, 2>(StateLayout::landmark(a), StateLayout::landmark(c)) += B;
      H.block<2, 2>(StateLayout::landmark(c), StateLayout::landmark(a)) += B.transpose();
    }
  }
};

}  // namespace

// A landmark's links: slots and blocks stay paired, in order, through erase and truncate.
TEST(LinkList, SlotsAndBlocksStayPairedInOrder) {
  LinkList links;
  for (int k = 0; k < 5; ++k) links.push_back(10 + k, LinkList::Block::Constant(static_cast<double>(k)));
  links.erase(links.at(12));
  links.setSlot(links.at(14), 7);
  ASSERT_EQ(links.size(), 4u);
  const std::vector<int> slots(links.slots().begin(), links.slots().end());
  EXPECT_EQ(slots, (std::vector<int>{10, 11, 13, 7}));
  const std::vector<double> values{0.0, 1.0, 3.0, 4.0};
  std::size_t i = 0;
  for (const LinkList::Ref l : links) {
    EXPECT_EQ(l.slot, slots[i]);
    EXPECT_EQ(l.H, LinkList::Block::Constant(values[i]));
    EXPECT_EQ(&l.H, &links.block(i));
    ++i;
  }
  EXPECT_EQ(i, links.size());
  EXPECT_EQ(links.find(12), links.size());
  EXPECT_THROW((void)links.at(12), std::logic_error);
  links.truncate(2);
  EXPECT_EQ(links.size(), 2u);
  EXPECT_EQ(links.slot(1), 11);
  EXPECT_EQ(links.block(1), LinkList::Block::Constant(1.0));
}

TEST(SeifStore, SparseInformationIsWhatWasAdded) {
  Fixture f(5);
  EXPECT_EQ(Eigen::MatrixXd(f.store.sparseInformation()), f.H);
  EXPECT_EQ(f.store.informationVector(), f.b);
  EXPECT_EQ(f.store.ids(), (std::vector<int>{10, 11, 12, 13, 14}));
  const Eigen::VectorXd mu = f.store.mean();
  EXPECT_EQ(mu.head<3>(), kRobotMean);
  EXPECT_EQ(mu.segment<2>(StateLayout::landmark(3)), Vec2(3, -3));
  const FilterStats s = f.store.stats();
  EXPECT_EQ(s.landmarks, 5u);
  EXPECT_EQ(s.robot_links, 5u);
  EXPECT_EQ(s.links, 5u + 3u);
  EXPECT_EQ(s.max_landmark_links, 3u);  // landmarks 0 and 1: the robot and two others
  EXPECT_EQ(s.blocks_touched, 5u * 3u);  // three blocks per observation
}

TEST(SeifStore, LinksAreSymmetricAndCountedOnce) {
  SeifStore store(kRobotH, kRobotMean);
  for (int s = 0; s < 3; ++s) store.addLandmark(s, Vec2::Zero());
  const Mat2 A{{1.0, 2.0}, {3.0, 4.0}}, B{{0.5, -1.0}, {0.25, 2.0}};
  EXPECT_EQ(store.findLink(0, 2), nullptr);
  store.addToLink(0, 2, A);
  store.addToLink(2, 0, B);  // the same link, seen from the other end
  ASSERT_NE(store.findLink(0, 2), nullptr);
  ASSERT_NE(store.findLink(2, 0), nullptr);
  EXPECT_EQ(*store.findLink(0, 2), Mat2(A + B.transpose()));
  EXPECT_EQ(*store.findLink(2, 0), Mat2(A.transpose() + B));
  EXPECT_EQ(store.findLink(0, 1), nullptr);
  EXPECT_EQ(store.node(0).links.size(), 1u);
  EXPECT_EQ(store.node(2).links.size(), 1u);
  EXPECT_EQ(store.stats().links, 1u);
  store.addToLink(1, 2, A);
  EXPECT_EQ(store.stats().links, 2u);
  EXPECT_EQ(store.stats().max_landmark_links, 2u);  // landmark 2
  const Eigen::MatrixXd H(store.sparseInformation());
  EXPECT_EQ(H, H.transpose());
}

TEST(SeifStore, GatherScatterRoundTripIsExact) {
  Fixture f(6);
  f.store.removeRobotLink(4);  // a passive landmark in the block too
  const Eigen::MatrixXd H_before(f.store.sparseInformation());
  const Eigen::VectorXd b_before = f.store.informationVector(), mu_before = f.store.mean();
  const std::vector<int> order{3, 0, 4, 1};
  f.store.gather(order);
  EXPECT_EQ(f.store.blocksTouched(), 6u * 3u + 25u);
  ASSERT_EQ(f.store.localH().rows(), 3 + 2 * 4);
  // The local block is the dense submatrix of H over [x, 3, 0, 4, 1].
  std::vector<int> rows{0, 1, 2};
  for (int s : order) {
    rows.push_back(StateLayout::landmark(s));
    rows.push_back(StateLayout::landmark(s) + 1);
  }
  for (std::size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(f.store.localB()(static_cast<Eigen::Index>(i)), b_before(rows[i]));
    EXPECT_EQ(f.store.localMean()(static_cast<Eigen::Index>(i)), mu_before(rows[i]));
    for (std::size_t j = 0; j < rows.size(); ++j) {
      EXPECT_EQ(f.store.localH()(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)),
                H_before(rows[i], rows[j]))
          << i << ", " << j;
    }
  }
  f.store.scatter();
  EXPECT_EQ(Eigen::MatrixXd(f.store.sparseInformation()), H_before);
  EXPECT_EQ(f.store.informationVector(), b_before);
  EXPECT_EQ(f.store.mean(), mu_before);
  EXPECT_EQ(f.store.stats().links, 5u + 3u);  // zero blocks created no link

  // A changed block comes back, a new non-zero block between landmarks becomes a link.
  f.store.gather(order);
  f.store.localH().block<2, 2>(3 + 2 * 2, 3 + 2 * 3) = Mat2::Identity();  // 4-1
  f.store.localH().block<2, 2>(3 + 2 * 3, 3 + 2 * 2) = Mat2::Identity();
  f.store.localB()(0) = 42.0;
  f.store.localMean()(3) = -7.0;  // landmark 3
  f.store.scatter();
  ASSERT_NE(f.store.findLink(4, 1), nullptr);
  EXPECT_EQ(*f.store.findLink(4, 1), Mat2::Identity());
  EXPECT_EQ(*f.store.findLink(1, 4), Mat2::Identity());
  EXPECT_EQ(f.store.stats().links, 5u + 4u);
  EXPECT_EQ(f.store.robotVector()(0), 42.0);
  EXPECT_EQ(f.store.node(3).mu(0), -7.0);
}

TEST(SeifStore, RemoveRobotLinkKeepsPositionsConsistent) {
  Fixture f(5);
  const Eigen::MatrixXd H_before(f.store.sparseInformation());
  for (int slot : {1, 4, 0}) {
    f.store.removeRobotLink(slot);
    EXPECT_EQ(f.store.node(slot).active, -1);
    const auto& links = f.store.robotLinks();
    for (std::size_t p = 0; p < links.size(); ++p) {
      EXPECT_EQ(f.store.node(links[p].slot).active, static_cast<int>(p));
    }
    // The robot link's block is gone from H, and nothing else.
    Eigen::MatrixXd expected = H_before;
    for (int s : {1, 4, 0}) {
      if (f.store.node(s).active >= 0) continue;
      expected.block<3, 2>(0, StateLayout::landmark(s)).setZero();
      expected.block<2, 3>(StateLayout::landmark(s), 0).setZero();
    }
    EXPECT_EQ(Eigen::MatrixXd(f.store.sparseInformation()), expected);
  }
  ASSERT_EQ(f.store.robotLinks().size(), 2u);
  std::vector<int> active{f.store.robotLinks()[0].slot, f.store.robotLinks()[1].slot};
  std::sort(active.begin(), active.end());
  EXPECT_EQ(active, (std::vector<int>{2, 3}));
  // Observing a passive landmark again makes it active at the end, seen at this step.
  f.store.beginStep();
  f.store.addObservation(4, Mat5::Identity(), Vec5::Zero());
  EXPECT_EQ(f.store.node(4).active, 2);
  EXPECT_EQ(f.store.robotLinks()[2].slot, 4);
  EXPECT_EQ(f.store.robotLinks()[2].last_seen, 1);
  EXPECT_EQ(f.store.robotLinks()[2].H, Mat32::Zero());  // Identity has no robot-landmark block
}

TEST(SeifStore, RelaxationConvergesToTheExactMean) {
  for (double omega : {1.0, 0.5, 1.9}) {  // Gauss-Seidel, under- and over-relaxed (SeifOptions::omega)
    Fixture f(6, 5);
    f.store.removeRobotLink(2);
    const Eigen::VectorXd exact =
        Eigen::MatrixXd(f.store.sparseInformation()).llt().solve(f.store.informationVector());
    const double start = (f.store.mean() - exact).norm();
    for (int sweep = 0; sweep < 400; ++sweep) {
      f.store.relaxRobot();
      std::vector<int> all{0, 1, 2, 3, 4, 5};
      for (int s : all) f.store.prefetch(s);
      f.store.relaxLandmarks(all, omega);
    }
    EXPECT_GT(start, 1.0);
    EXPECT_LT((f.store.mean() - exact).norm(), 1e-9 * start) << "omega " << omega;
  }
}

TEST(SeifStore, JointSolveOfTheActiveBlock) {
  Fixture f(6, 5);
  const Eigen::MatrixXd H(f.store.sparseInformation());
  const Eigen::VectorXd b = f.store.informationVector();
  // Every landmark active: the block is the whole state and one solve is exact.
  f.store.relaxActive();
  const Eigen::VectorXd exact = H.llt().solve(b);
  EXPECT_LT((f.store.mean() - exact).norm(), 1e-12 * exact.norm());
  // Landmark 2 passive: the block's mean given mu_2, eq. (42) with L = {x, active}.
  f.store.removeRobotLink(2);
  f.store.setMean(Eigen::VectorXd::Zero(b.size()));
  f.store.relaxActive();
  const Eigen::VectorXd mu = f.store.mean();
  EXPECT_EQ(mu.segment<2>(StateLayout::landmark(2)), Vec2::Zero());
  const Eigen::MatrixXd H2(f.store.sparseInformation());
  const Eigen::VectorXd r = H2 * mu - b;  // zero except in landmark 2's rows
  EXPECT_LT(r.head(StateLayout::landmark(2)).norm(), 1e-12 * b.norm());
  EXPECT_LT(r.tail(r.size() - StateLayout::landmark(3)).norm(), 1e-12 * b.norm());
  EXPECT_GT(r.segment<2>(StateLayout::landmark(2)).norm(), 1e-3);
}

TEST(SeifStore, TheIteratedUpdatesBlockStaysTheStoresAndReordersAsAGather) {
  // The iterated update gathers once: addObservationInBlock() changes the store and the block
  // alike, solveLocalMean(Reuse) keeps the passive terms, reorderGathered() permutes the block.
  Fixture f(6, 7);
  std::mt19937_64 rng(9);
  f.store.removeRobotLink(2);  // passive, linked to active 1
  f.store.removeRobotLink(3);  // passive, linked to active 0
  Eigen::VectorXd mu(f.b.size());
  std::normal_distribution<double> n01;
  for (Eigen::Index i = 0; i < mu.size(); ++i) mu(i) = n01(rng);
  f.store.setMean(mu);
  f.store.gatherActive();
  EXPECT_THROW(f.store.solveLocalMean(SeifStore::Passive::Reuse), std::logic_error);  // nothing to reuse yet
  f.store.solveLocalMean(SeifStore::Passive::Recompute);
  const std::vector<int> block(f.store.gathered().begin(), f.store.gathered().end());
  const auto [dH, db] = randomInformation(rng);
  f.store.addObservationInBlock(block[1], dH, db);
  EXPECT_THROW(f.store.addObservationInBlock(2, dH, db), std::logic_error);  // passive: outside
  const LocalMatrix H_kept = f.store.localH();
  const LocalVector b_kept = f.store.localB();
  f.store.solveLocalMean(SeifStore::Passive::Reuse);
  const Eigen::VectorXd mean_kept = f.store.mean();
  // A fresh gather of the same store: the same block, bit for bit, and the same solution.
  f.store.gatherActive();
  EXPECT_EQ(f.store.localH(), H_kept);
  EXPECT_EQ(f.store.localB(), b_kept);
  f.store.solveLocalMean(SeifStore::Passive::Recompute);
  EXPECT_LT((f.store.mean() - mean_kept).norm(), 1e-12 * mean_kept.norm());
  // Reordered: as gathered in that order.
  std::vector<int> reversed(block.rbegin(), block.rend());
  f.store.reorderGathered(reversed);
  const LocalMatrix H_reordered = f.store.localH();
  const LocalVector b_reordered = f.store.localB();
  f.store.solveLocalMean(SeifStore::Passive::Reuse);
  const Eigen::VectorXd mean_reordered = f.store.mean();
  f.store.gather(reversed);
  EXPECT_EQ(f.store.localH(), H_reordered);
  EXPECT_EQ(f.store.localB(), b_reordered);
  f.store.solveLocalMean(SeifStore::Passive::Recompute);
  EXPECT_LT((f.store.mean() - mean_reordered).norm(), 1e-12 * mean_reordered.norm());
  EXPECT_THROW(f.store.reorderGathered(std::vector<int>{0, 1}), std::logic_error);  // other landmarks
}

TEST(SeifStore, RejectsABlockLargerThanTheLocalBuffers) {
  SeifStore store(kRobotH, kRobotMean);
  std::vector<int> slots;
  for (int s = 0; s <= kMaxLocalLandmarks; ++s) slots.push_back(store.addLandmark(s, Vec2::Zero()));
  EXPECT_THROW(store.gather(slots), seif::InvalidArgument);
  slots.pop_back();
  store.gather(slots);
  EXPECT_EQ(store.localH().rows(), kMaxLocalDim);
}

namespace {

TEST(SeifStore, RejectsALandmarkListedTwiceInABlockAndStaysUsable) {
  Fixture f(4);
  const Eigen::MatrixXd H_before(f.store.sparseInformation());
  const std::vector<int> twice{0, 2, 0};
  EXPECT_THROW(f.store.gather(twice), seif::InvalidArgument);
  // A position mark left behind would refuse the next block as listing a landmark twice.
  const std::vector<int> order{2, 0, 1};
  EXPECT_NO_THROW(f.store.gather(order));
  f.store.scatter();
  EXPECT_NO_THROW(f.store.gather(order));
  f.store.scatter();
  EXPECT_EQ(Eigen::MatrixXd(f.store.sparseInformation()), H_before);
}

}  // namespace
