# Reference values for tests/analysis/learning_curve_test.cpp: R's nls() fits of the
# exponential and power laws of practice, their standard errors (summary()) and 95 %
# intervals estimate ± qt(0.975, df) × SE. The tests hold the printed numbers; they do not
# need R. Produced with R 4.2.2:  cd tests/analysis && LC_ALL=C Rscript learning_curve_reference.R
f <- function(x) paste(sprintf("%.17g", x), collapse = ", ")
n <- 1:11
set.seed(42)
y <- round(2 + 6 * exp(-0.35 * (n - 1)) + rnorm(11, 0, 0.25), 3)
cat(sprintf("// scores: %s\n", f(y)))
fits <- list(
  exponential = nls(y ~ a + b * exp(-c * (n - 1)), start = list(a = 2, b = 6, c = 0.3),
                    control = nls.control(tol = 1e-7, maxiter = 500, minFactor = 1e-10)),
  power = nls(y ~ a + b * n^(-c), start = list(a = 0, b = 8, c = 0.5),
              control = nls.control(tol = 1e-7, maxiter = 500, minFactor = 1e-10)))
for (law in names(fits)) {
  m <- fits[[law]]
  s <- summary(m)$coefficients
  t <- qt(0.975, df.residual(m))
  cat(sprintf("// %s: rss %s, sigma %s\n", law, f(deviance(m)), f(summary(m)$sigma)))
  for (p in c("a", "b", "c")) {
    cat(sprintf("//   %s: %s, se %s, ci [%s, %s]\n", p, f(s[p, "Estimate"]), f(s[p, "Std. Error"]),
                f(s[p, "Estimate"] - t * s[p, "Std. Error"]), f(s[p, "Estimate"] + t * s[p, "Std. Error"])))
  }
}
