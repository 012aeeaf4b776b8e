// CHOLMOD backend: sparse Cholesky of the SparseSystem's upper triangle, wrapped in place (no copy
// of the system per step). One cholmod_common per solver; the symbolic analysis (ordering,
// elimination tree, supernodes) is kept in the cholmod_factor and reused by every factorize until
// the pattern changes; solves reuse CHOLMOD's solution and workspace (cholmod_solve2).
// CHOLMOD picks supernodal LL^T for 3D tet meshes of a few thousand nodes and up (later where
// laid out for solves: CholmodLayout); it uses the system BLAS (OpenBLAS is about 2.5x faster
// there than the reference BLAS). Its OpenMP loops run on the calling thread (CallingThreadOnly
// below).
#if SOFTHAP_WITH_CHOLMOD

#include "linalg/linear_solver.hpp"

#include "core/error.hpp"

#include <cholmod.h>
#include <dlfcn.h>

#include <cstring>

namespace sh {
namespace {

const char* cholmod_status_text(int status) {
    switch (status) {
        case CHOLMOD_OK: return "ok";
        case CHOLMOD_NOT_INSTALLED: return "method not installed";
        case CHOLMOD_OUT_OF_MEMORY: return "out of memory";
        case CHOLMOD_TOO_LARGE: return "problem too large";
        case CHOLMOD_INVALID: return "invalid input";
        case CHOLMOD_GPU_PROBLEM: return "GPU problem";
        case CHOLMOD_NOT_POSDEF: return "not positive definite";
        case CHOLMOD_DSMALL: return "tiny diagonal";
        default: return "unknown status";
    }
}

// Debian's CHOLMOD 3 runs the supernodal factorisation's loops in OpenMP regions with a fixed
// num_threads(4) clause, which OMP_NUM_THREADS cannot lower; on 2 cores the threads spin against
// each other and the sim thread's neighbours (raptor, 19 k tets, StVK: 87 ms per factorisation
// with them, 37-40 ms on one thread). For the scope of a CHOLMOD call this turns on the calling
// thread's dynamic adjustment with a thread count of 1, under which the OpenMP runtime gives such
// regions a single thread, and restores both after: the host's own OpenMP settings (per thread)
// are untouched. The runtime's functions are looked up in whatever OpenMP runtime CHOLMOD
// loaded; without one this does nothing.
class CallingThreadOnly {
public:
    CallingThreadOnly() {
        const Runtime& omp = runtime();
        if (!omp.available) return;
        dynamic_ = omp.get_dynamic();
        threads_ = omp.get_max_threads();
        omp.set_dynamic(1);
        omp.set_num_threads(1);
    }
    ~CallingThreadOnly() {
        const Runtime& omp = runtime();
        if (!omp.available) return;
        omp.set_num_threads(threads_);
        omp.set_dynamic(dynamic_);
    }
    CallingThreadOnly(const CallingThreadOnly&) = delete;             ///< a scope guard
    CallingThreadOnly& operator=(const CallingThreadOnly&) = delete;  ///< a scope guard

private:
    struct Runtime {
        int (*get_dynamic)() = nullptr;
        int (*get_max_threads)() = nullptr;
        void (*set_dynamic)(int) = nullptr;
        void (*set_num_threads)(int) = nullptr;
        bool available = false;
    };
    static const Runtime& runtime() {
        static const Runtime found = [] {
            Runtime r;
            r.get_dynamic = reinterpret_cast<int (*)()>(dlsym(RTLD_DEFAULT, "omp_get_dynamic"));
            r.get_max_threads = reinterpret_cast<int (*)()>(dlsym(RTLD_DEFAULT, "omp_get_max_threads"));
            r.set_dynamic = reinterpret_cast<void (*)(int)>(dlsym(RTLD_DEFAULT, "omp_set_dynamic"));
            r.set_num_threads = reinterpret_cast<void (*)(int)>(dlsym(RTLD_DEFAULT, "omp_set_num_threads"));
            r.available = r.get_dynamic && r.get_max_threads && r.set_dynamic && r.set_num_threads;
            return r;
        }();
        return found;
    }
    int dynamic_ = 0, threads_ = 1;
};

class CholmodSolver final : public LinearSolver {
public:
    explicit CholmodSolver(CholmodLayout layout) {
        cholmod_start(&common_);
        if (layout == CholmodLayout::ForSolves) common_.supernodal_switch = kSolvesSupernodalSwitch;
        common_.print = 0;  // never print (errors come back as sh::Error)
        common_.error_handler = nullptr;
        // Keep the factor as computed (supernodal LL^T or simplicial LDL^T): no conversion pass.
        common_.final_asis = 1;
    }

    ~CholmodSolver() override {
        free_all();
        cholmod_finish(&common_);
    }

    CholmodSolver(const CholmodSolver&) = delete;
    CholmodSolver& operator=(const CholmodSolver&) = delete;

    const char* name() const override { return "cholmod"; }
    bool is_direct() const override { return true; }

protected:
    void do_analyze(const SparseSystem& a, const EliminationOrder* suggested) override {
        free_all();
        cholmod_sparse matrix = wrap(a);
        const double nodes = static_cast<double>(a.dof_count() / 3);
        if (suggested) factor_ = analyze_in_order(matrix, *suggested);
        if (factor_) {
            fill_per_node_ = suggested->fill_per_node;
            flops_per_node_ = suggested->flops_per_node;
        } else {
            factor_ = cholmod_analyze(&matrix, &common_);
            check(factor_ != nullptr, "symbolic analysis");
            fill_per_node_ = common_.lnz / nodes;
            flops_per_node_ = common_.fl / nodes;
        }
        // common_ holds the analysis of the order kept (cholmod_analyze_p sets both).
        estimated_work_ = factor_work(common_.fl, common_.lnz, factor_->is_super ? kSupernodalSpeed : 1.0);
    }

    bool do_elimination_order(EliminationOrder& out) const override {
        // AMD orders a node's three DOFs together (they have the same neighbours), so the
        // node order is the order of each node's first DOF.
        const size_t nodes = factor_->n / 3;
        const int* perm = static_cast<const int*>(factor_->Perm);
        vec<int32_t> order;
        order.reserve(nodes);
        vec<uint8_t> seen(nodes, 0);
        for (size_t k = 0; k < factor_->n; ++k) {
            const size_t node = static_cast<size_t>(perm[k]) / 3;
            if (!seen[node]) order.push_back(static_cast<int32_t>(node));
            seen[node] = 1;
        }
        out.nodes.swap(order);
        out.fill_per_node = fill_per_node_;
        out.flops_per_node = flops_per_node_;
        return true;
    }
    void do_factorize(const SparseSystem& a) override {
        const CallingThreadOnly serial;
        cholmod_sparse matrix = wrap(a);
        const int ok = cholmod_factorize(&matrix, factor_, &common_);
        size_t minor = factor_->minor;
        if (ok && minor >= factor_->n && !factor_->is_super && !factor_->is_ll) {
            // Simplicial LDL^T only stops at a zero pivot (an indefinite matrix factorises);
            // we need positive definite, so check D: the first entry of each column of L.
            const int* lp = static_cast<const int*>(factor_->p);
            const double* lx = static_cast<const double*>(factor_->x);
            for (size_t k = 0; k < factor_->n; ++k)
                if (!(lx[lp[k]] > 0.0)) {
                    minor = k;
                    break;
                }
        }
        if (common_.status == CHOLMOD_NOT_POSDEF || minor < factor_->n) {
            // minor is the failing column of the permuted matrix P A P^T; Perm maps it back.
            const int* perm = static_cast<const int*>(factor_->Perm);
            const int32_t column = perm && minor < factor_->n ? perm[minor] : static_cast<int32_t>(minor);
            solver_detail::throw_not_positive_definite(
                a, column, name(),
                format("%s factorisation stopped at elimination step %zu", factor_->is_super ? "supernodal" : "simplicial",
                       minor)
                    .c_str());
        }
        check(ok != 0, "numeric factorisation");
    }

    int do_solve(const SparseSystem& a, const double* b, double* x) override {
        const CallingThreadOnly serial;
        const size_t n = static_cast<size_t>(a.dof_count());
        // b wrapped in place; X, Y and E are kept between calls, so after the first solve
        // cholmod_solve2 allocates nothing.
        cholmod_dense rhs;
        std::memset(&rhs, 0, sizeof rhs);
        rhs.nrow = n;
        rhs.ncol = 1;
        rhs.nzmax = n;
        rhs.d = n;
        rhs.x = const_cast<double*>(b);
        rhs.xtype = CHOLMOD_REAL;
        rhs.dtype = CHOLMOD_DOUBLE;
        if (work_y_ && !factor_->is_super && work_y_->nzmax >= 4 * n) {
            // The simplicial solve asks for a 4 x n Y, then relabels it 1 x n for one right-hand
            // side, so the next call would free and reallocate it; restore the shape it asks
            // for (same memory, nzmax >= 4n) so Y really is reused.
            work_y_->nrow = 4;
            work_y_->ncol = n;
            work_y_->d = 4;
        }
        const int ok =
            cholmod_solve2(CHOLMOD_A, factor_, &rhs, nullptr, &solution_, nullptr, &work_y_, &work_e_, &common_);
        check(ok != 0 && solution_ != nullptr, "solve");
        std::memcpy(x, solution_->x, n * sizeof(double));
        return 1;
    }

private:
    // How many times a solve's operations per second a supernodal factorisation does (BLAS-3
    // over supernodes, OpenBLAS): 4.3 to 7.4 measured on 17,800 and 11,500 DOF systems. A
    // simplicial factorisation runs the same scalar loops as a solve: counted at its speed.
    static constexpr double kSupernodalSpeed = 6.0;

    // The symbolic analysis of matrix in the suggested node order (each node's DOFs together),
    // or null if that order's fill or flops exceed what kSuggestedOrderTolerance allows: a fresh
    // ordering then pays for itself within a few factorisations.
    cholmod_factor* analyze_in_order(cholmod_sparse& matrix, const EliminationOrder& order) {
        const size_t nodes = order.nodes.size();
        vec<int32_t> perm(3 * nodes);
        for (size_t k = 0; k < nodes; ++k)
            for (int32_t c = 0; c < 3; ++c) perm[3 * k + static_cast<size_t>(c)] = 3 * order.nodes[k] + c;
        const int methods = common_.nmethods;
        const int ordering = common_.method[0].ordering;
        common_.nmethods = 1;
        common_.method[0].ordering = CHOLMOD_GIVEN;
        cholmod_factor* factor = cholmod_analyze_p(&matrix, perm.data(), nullptr, 0, &common_);
        common_.nmethods = methods;
        common_.method[0].ordering = ordering;
        check(factor != nullptr, "symbolic analysis in a given order");
        const double allowed = kSuggestedOrderTolerance * static_cast<double>(nodes);
        const bool fills = order.fill_per_node > 0.0 && common_.lnz > allowed * order.fill_per_node;
        const bool slows = order.flops_per_node > 0.0 && common_.fl > allowed * order.flops_per_node;
        if (fills || slows) cholmod_free_factor(&factor, &common_);
        return factor;
    }

    // The system's upper triangle as a packed, sorted, stype = 1 CHOLMOD matrix over its arrays.
    // CHOLMOD only reads an input matrix, so the const_casts are safe.
    static cholmod_sparse wrap(const SparseSystem& a) {
        cholmod_sparse m;
        std::memset(&m, 0, sizeof m);
        m.nrow = static_cast<size_t>(a.dof_count());
        m.ncol = m.nrow;
        m.nzmax = static_cast<size_t>(a.nonzero_count());
        m.p = const_cast<int32_t*>(a.column_starts().data());
        m.i = const_cast<int32_t*>(a.row_indices().data());
        m.nz = nullptr;
        m.x = const_cast<double*>(a.values().data());
        m.z = nullptr;
        m.stype = 1;
        m.itype = CHOLMOD_INT;
        m.xtype = CHOLMOD_REAL;
        m.dtype = CHOLMOD_DOUBLE;
        m.sorted = 1;
        m.packed = 1;
        return m;
    }

    void check(bool ok, const char* what) {
        if (ok && common_.status >= CHOLMOD_OK) return;
        const int status = common_.status;
        if (status == CHOLMOD_OUT_OF_MEMORY) throw std::bad_alloc();
        throw Error(status == CHOLMOD_TOO_LARGE ? SH_ERR_CAPACITY : SH_ERR_SOLVER,
                    format("cholmod: %s failed: %s (status %d)", what, cholmod_status_text(status), status));
    }

    void free_all() {
        if (factor_) cholmod_free_factor(&factor_, &common_);
        if (solution_) cholmod_free_dense(&solution_, &common_);
        if (work_y_) cholmod_free_dense(&work_y_, &common_);
        if (work_e_) cholmod_free_dense(&work_e_, &common_);
    }

    cholmod_common common_;
    cholmod_factor* factor_ = nullptr;
    double fill_per_node_ = 0.0;   // the last fresh ordering's factor entries per node (CHOLMOD's lnz)
    double flops_per_node_ = 0.0;  // and its factorisation's floating-point operations (CHOLMOD's fl)
    cholmod_dense* solution_ = nullptr;
    cholmod_dense* work_y_ = nullptr;
    cholmod_dense* work_e_ = nullptr;
};

}  // namespace

LinearSolverPtr make_cholmod_solver(CholmodLayout layout) { return LinearSolverPtr(create<CholmodSolver>(layout)); }

}  // namespace sh

#endif  // SOFTHAP_WITH_CHOLMOD
